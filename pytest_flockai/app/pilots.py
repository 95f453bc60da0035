"""The pilots an app's commands fly: a setpoint follower (offboard position or velocity
setpoints, reposition, hold, all with a heading) and a wrapper that flies a leg of a
mission without ending the plan when the leg is done (the autopilot moves on).

``Setpoint`` moves a reference point toward the commanded position (speed-limited,
acceleration-limited) or at the commanded velocity and writes it, its velocity and
acceleration as the controller's setpoint, as PX4's position controller smooths a
setpoint step into a trajectory it can follow.
"""

from __future__ import annotations

import math

from ..control.pilots import Orbit, Pilot

#: m/s: vertical speed limit (PX4 MPC_Z_VEL_MAX_UP default 3 m/s)
Z_SPEED = 3.0
#: MAV_CMD_DO_ORBIT param 3 (ORBIT_YAW_BEHAVIOUR) -> the heading flown: 0 front to the
#: centre, 1 the heading when commanded, 2 uncontrolled (nothing turns the drone: it
#: keeps that heading too), 3 front along the circle; 4 (RC) is not emulated; 5
#: (unchanged) keeps an orbit's own; not given (NaN): PX4's MC_ORBIT_YAW_MOD default, 0
ORBIT_YAW = {0: "center", 1: "initial", 2: "initial", 3: "tangent"}
#: 1/s: the position gain that turns the distance to a position setpoint into a speed
GAIN = 1.0
#: rad/s: the fastest yaw rate a setpoint turns at (PX4's MC_YAWRATE_MAX default, 200 deg/s)
YAW_RATE_MAX = math.radians(200.0)


class Setpoint(Pilot):
    """Fly to ``pos`` (x, y, z) or at ``vel`` (vx, vy, vz), heading ``yaw`` (rad,
    the simulator's; None: keep the heading) or turning at ``yaw_rate`` (rad/s,
    counter-clockwise seen from above, at most ``YAW_RATE_MAX``); never done."""

    def __init__(self, altitude: float, speed: float, pos=None, vel=None,
                 yaw: float | None = None, yaw_rate: float | None = None):
        self.altitude, self.speed = float(altitude), float(speed)
        self.pos, self.vel, self.yaw = pos, vel, yaw
        self.yaw_rate = _rate(yaw_rate)
        self.path_length = None

    def set(self, pos=None, vel=None, yaw=None, speed=None, yaw_rate=None) -> None:
        """A new setpoint (from the app); ``yaw`` None keeps the one flown, turning at
        ``yaw_rate`` where one is given."""
        self.pos, self.vel = pos, vel
        if yaw is not None:
            self.yaw = yaw
        self.yaw_rate = _rate(yaw_rate)
        if speed is not None and speed > 0:
            self.speed = float(speed)

    def start(self, t, position, accel):
        self.t0 = self._t = t
        self._p = [position[0], position[1], position[2]]
        self._v = [0.0, 0.0, 0.0]
        self._accel = accel
        self._yaw0 = 0.0

    def reached(self, radius: float) -> bool:
        """The reference point is within ``radius`` m of the position setpoint and slow."""
        if self.pos is None:
            return False
        return (math.dist(self._p, self.pos) <= radius
                and math.hypot(*self._v) < 0.5)

    def update(self, t, state, sp):
        dt = max(0.0, t - self._t)
        self._t = t
        p, v = self._p, self._v
        if self.pos is not None:      # toward it, slow enough to brake at half the limit
            d = [self.pos[i] - p[i] for i in range(3)]
            dist = math.sqrt(d[0] ** 2 + d[1] ** 2 + d[2] ** 2)
            s = min(GAIN * dist, math.sqrt(self._accel * dist))
            w = [c * s / dist for c in d] if dist > 1e-9 else [0.0, 0.0, 0.0]
        elif self.vel is not None:
            w = list(self.vel)
        else:
            w = [0.0, 0.0, 0.0]
        h = math.hypot(w[0], w[1])
        if h > self.speed:
            w[0], w[1] = w[0] * self.speed / h, w[1] * self.speed / h
        w[2] = max(-Z_SPEED, min(Z_SPEED, w[2]))
        dv = [w[i] - v[i] for i in range(3)]
        dn = math.sqrt(dv[0] ** 2 + dv[1] ** 2 + dv[2] ** 2)
        lim = self._accel * dt
        if dn > lim > 0.0:
            dv = [d * lim / dn for d in dv]
        for i in range(3):
            sp[6 + i] = dv[i] / dt if dt > 0.0 else 0.0
            v[i] += dv[i]
            p[i] += v[i] * dt
            sp[i], sp[3 + i] = p[i], v[i]
        if self.yaw_rate is not None:
            y = (self._yaw0 if self.yaw is None else self.yaw) + self.yaw_rate * dt
            self.yaw = (y + math.pi) % (2.0 * math.pi) - math.pi
        sp[9] = self._yaw0 if self.yaw is None else self.yaw
        return False

    def to_dict(self):
        return {"type": "Setpoint", "pos": self.pos, "vel": self.vel, "yaw": self.yaw,
                "yaw_rate": self.yaw_rate}


def _rate(r) -> float | None:
    return None if r is None else max(-YAW_RATE_MAX, min(YAW_RATE_MAX, float(r)))


class Leg(Pilot):
    """Fly ``inner`` (a pilot) and remember when it is done (``done``), without ending
    the flight plan: the autopilot decides what comes next."""

    def __init__(self, inner: Pilot):
        self.inner, self.altitude = inner, inner.altitude
        self.speed = getattr(inner, "speed", 5.0)
        self.done = False
        self.path_length = None

    def start(self, t, position, accel):
        self.t0 = t
        self.inner.start(t, position, accel)

    def update(self, t, state, sp):
        if self.inner.update(t, state, sp):
            self.done = True
        return False

    def to_dict(self):
        return {"type": "Leg", "inner": self.inner.to_dict()}


class AppOrbit(Pilot):
    """MAV_CMD_DO_ORBIT: circle ``center`` (x, y) at ``altitude``, ``speed`` m/s,
    clockwise seen from above for a positive ``radius`` and counter-clockwise for a
    negative one (MAVLink's sign convention), heading by ``yaw_mode`` (``ORBIT_YAW``:
    0, 1, 2 or 3), ``yaw0`` the heading when commanded (rad); never done. Flies
    ``control.pilots.Orbit`` (counter-clockwise) mirrored across the centre's
    east-west line for a clockwise orbit."""

    def __init__(self, center, radius: float, altitude: float, speed: float,
                 yaw_mode: int = 0, yaw0: float = 0.0):
        self.inner = Orbit(center, abs(radius), altitude, speed)
        self.clockwise = radius > 0
        self.center, self.radius = self.inner.center, float(radius)
        self.altitude, self.speed = self.inner.altitude, self.inner.speed
        self.yaw_mode, self.yaw0 = int(yaw_mode), float(yaw0)
        self.path_length = None

    def start(self, t, position, accel):
        self.t0 = t
        y = 2 * self.center[1] - position[1] if self.clockwise else position[1]
        self.inner.start(t, (position[0], y, position[2]), accel)
        self._yaw = self.yaw0

    def update(self, t, state, sp):
        self.inner.update(t, state, sp)
        cx, cy = self.center
        if self.clockwise:                  # mirrored: y, vy and ay change sign about cy
            sp[1], sp[4], sp[7] = 2 * cy - sp[1], -sp[4], -sp[7]
        how = ORBIT_YAW[self.yaw_mode]
        if how == "center" and math.hypot(cx - sp[0], cy - sp[1]) > 0.5:
            self._yaw = math.atan2(cy - sp[1], cx - sp[0])
        elif how == "tangent" and math.hypot(sp[3], sp[4]) > 0.1:
            self._yaw = math.atan2(sp[4], sp[3])
        sp[9] = self._yaw
        return False

    def to_dict(self):
        return {"type": "AppOrbit", "center": list(self.center), "radius": self.radius,
                "altitude": self.altitude, "speed": self.speed, "yaw_mode": self.yaw_mode}
