"""Frames and names of the MAVLink front-end: the simulator's world (x east, y north,
z up, yaw counter-clockwise from east) against MAVLink's local NED frame (x north,
y east, z down, yaw clockwise from north) and WGS84 latitude/longitude, plus the
PX4 flight modes an app reads from the heartbeat.

The home position is PX4 SITL's default (47.397742 N, 8.545594 E, 488 m AMSL, the
``PX4_HOME_LAT/LON/ALT`` defaults of PX4-Autopilot's SITL start scripts); positions
around it use a flat-earth approximation (metres per degree from the WGS84 mean
radius 6,371,008.8 m), exact to centimetres over the few kilometres a test flies.
"""

from __future__ import annotations

import math

HOME_LAT, HOME_LON, HOME_AMSL = 47.397742, 8.545594, 488.0
EARTH_R = 6371008.8

# PX4 custom modes (px4_custom_mode.h): main mode in bits 16..23, sub mode in 24..31
MAIN = {"MANUAL": 1, "ALTCTL": 2, "POSCTL": 3, "AUTO": 4, "ACRO": 5, "OFFBOARD": 6,
        "STABILIZED": 7}
AUTO_SUB = {"READY": 1, "TAKEOFF": 2, "LOITER": 3, "MISSION": 4, "RTL": 5, "LAND": 6}
#: the modes this front-end flies, by name: (main, sub)
MODES = {"HOLD": (4, 3), "TAKEOFF": (4, 2), "MISSION": (4, 4), "RTL": (4, 5), "LAND": (4, 6),
         "OFFBOARD": (6, 0), "POSCTL": (3, 0), "ORBIT": (3, 1), "READY": (4, 1)}


def custom_mode(name: str) -> int:
    main, sub = MODES[name]
    return (main << 16) | (sub << 24)


def mode_name(main: int, sub: int) -> str | None:
    """The mode a DO_SET_MODE asks for, or None when it is not one flown here."""
    for name, (m, s) in MODES.items():
        if m == int(main) and (s == int(sub) or (s == 0 and name in ("OFFBOARD", "POSCTL"))):
            return name
    return None


class Geo:
    """Conversions around the home position ``home`` = (x, y, z) of the simulator."""

    def __init__(self, home, lat0: float = HOME_LAT, lon0: float = HOME_LON,
                 amsl0: float = HOME_AMSL):
        self.home = home
        self.lat0, self.lon0, self.amsl0 = lat0, lon0, amsl0
        self.m_lat = math.radians(1.0) * EARTH_R
        self.m_lon = self.m_lat * math.cos(math.radians(lat0))

    def to_global(self, x: float, y: float, z: float) -> tuple[float, float, float, float]:
        """(lat deg, lon deg, altitude AMSL m, altitude above home m) of a world point."""
        hx, hy, hz = self.home
        rel = z - hz
        return (self.lat0 + (y - hy) / self.m_lat, self.lon0 + (x - hx) / self.m_lon,
                self.amsl0 + rel, rel)

    def to_world(self, lat: float, lon: float, rel_alt: float) -> tuple[float, float, float]:
        """The world point of (lat, lon) at ``rel_alt`` m above home."""
        hx, hy, hz = self.home
        return (hx + (lon - self.lon0) * self.m_lon, hy + (lat - self.lat0) * self.m_lat,
                hz + rel_alt)

    def ned_to_world(self, n: float, e: float, d: float) -> tuple[float, float, float]:
        hx, hy, hz = self.home
        return hx + e, hy + n, hz - d

    def world_to_ned(self, x: float, y: float, z: float) -> tuple[float, float, float]:
        hx, hy, hz = self.home
        return y - hy, x - hx, hz - z


def yaw_ned(yaw_enu: float) -> float:
    """Heading clockwise from north (rad, -pi..pi) of a yaw counter-clockwise from east."""
    return math.atan2(math.cos(yaw_enu), math.sin(yaw_enu))


def yaw_enu(yaw_ned_rad: float) -> float:
    """The simulator's yaw of a heading clockwise from north (rad)."""
    return math.atan2(math.cos(yaw_ned_rad), math.sin(yaw_ned_rad))


def euler_ned(q) -> tuple[float, float, float]:
    """(roll, pitch, yaw) of a body (x forward, y left, z up) in the world frame,
    quaternion (w, x, y, z), as MAVLink's ATTITUDE reports them (FRD body in NED)."""
    w, x, y, z = q
    roll = math.atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2.0 * (w * y - z * x))))
    yaw = math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    return roll, -pitch, yaw_ned(yaw)
