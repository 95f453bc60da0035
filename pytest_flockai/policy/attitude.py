"""The drone's attitude as a policy sees it (``Cockpit.attitude``) and the heading a
``Cockpit.goto`` holds: roll, pitch and yaw from the navigation state's quaternion.

Angles are in radians in the simulator's frame (x east, y north, z up): ``yaw`` is
counter-clockwise from +x (east), as ``Cockpit.yaw``; ``roll`` is about the body's
forward axis (positive: left side up, banking right), ``pitch`` about its left axis
(positive: nose down, as the drone tilts to fly forward). ``heading_deg`` is the
compass heading (degrees clockwise from north, 0-360), as MAVLink's
GLOBAL_POSITION_INT ``hdg`` and a ground station show it."""

from __future__ import annotations

import math
import numbers

from ..errors import ConfigError


class Attitude:
    """``roll``, ``pitch``, ``yaw`` (rad) and ``heading_deg`` (module docstring)."""

    __slots__ = ("roll", "pitch", "yaw", "heading_deg")

    def __init__(self, roll: float, pitch: float, yaw: float):
        self.roll, self.pitch, self.yaw = roll, pitch, yaw
        self.heading_deg = (90.0 - math.degrees(yaw)) % 360.0

    def __iter__(self):
        return iter((self.roll, self.pitch, self.yaw))

    def __repr__(self):
        return (f"Attitude(roll={math.degrees(self.roll):.1f} deg, pitch="
                f"{math.degrees(self.pitch):.1f} deg, heading={self.heading_deg:.1f} deg)")


def attitude_of(quat) -> Attitude:
    """The ``Attitude`` of a unit quaternion (w, x, y, z), body to world (Z-Y-X Euler
    angles: yaw, then pitch, then roll)."""
    w, x, y, z = (float(c) for c in quat)
    roll = math.atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    s = max(-1.0, min(1.0, 2.0 * (w * y - z * x)))
    yaw = math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    return Attitude(roll, math.asin(s), yaw)


def goto_yaw(policy: str, yaw) -> float | None:
    """``yaw`` of ``Cockpit.goto`` checked: None (the plan's heading, 0: east) or a
    finite angle in radians, wrapped to (-pi, pi]."""
    if yaw is None:
        return None
    if isinstance(yaw, bool) or not isinstance(yaw, numbers.Real) or not math.isfinite(yaw):
        raise ConfigError(f"policy {policy!r}: goto(yaw = {yaw!r}) is not allowed; expected "
                          f"None or a finite angle in radians (counter-clockwise from east)")
    return math.atan2(math.sin(float(yaw)), math.cos(float(yaw)))
