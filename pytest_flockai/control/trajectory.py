"""Straight legs with a trapezoidal speed profile (accelerate, cruise, brake).

A ``Leg`` is a pure function of time: ``fill(t, sp)`` writes position,
velocity and acceleration feed-forward into the setpoint list ``sp``
(px py pz vx vy vz ax ay az yaw) without allocating.
"""

from __future__ import annotations

import math

from .._xp import MATH


def leg_timing(length, speed, accel, xp=MATH):
    """(cruise speed, t_acc, s_acc, t_cruise, duration) of a trapezoidal leg of ``length``
    > 0 (triangular when too short to reach ``speed``)."""
    v = xp.minimum(speed, xp.sqrt(length * accel))
    t_acc = v / accel
    s_acc = 0.5 * accel * t_acc ** 2
    t_cruise = (length - 2.0 * s_acc) / v
    return v, t_acc, s_acc, t_cruise, 2.0 * t_acc + t_cruise


class Leg:
    __slots__ = ("p0", "p1", "u", "length", "v", "a", "t_acc", "t_cruise", "duration", "s_acc")

    def __init__(self, p0, p1, speed: float, accel: float):
        self.p0 = tuple(float(c) for c in p0)
        self.p1 = tuple(float(c) for c in p1)
        d = [b - a for a, b in zip(self.p0, self.p1)]
        L = math.sqrt(sum(c * c for c in d))
        self.length = L
        self.u = tuple(c / L for c in d) if L > 1e-12 else (0.0, 0.0, 0.0)
        self.a = accel
        if L <= 1e-12:
            self.v = 0.0
            self.t_acc = self.t_cruise = self.duration = self.s_acc = 0.0
            return
        self.v, self.t_acc, self.s_acc, self.t_cruise, self.duration = leg_timing(L, speed, accel)

    def fill(self, t: float, sp) -> None:
        """Write the reference at time t (s since the leg began) into sp[0:9]."""
        a, v, ta = self.a, self.v, self.t_acc
        if t <= 0.0:
            s, sv, sa = 0.0, 0.0, 0.0
        elif t < ta:
            s, sv, sa = 0.5 * a * t * t, a * t, a
        elif t < ta + self.t_cruise:
            s, sv, sa = self.s_acc + v * (t - ta), v, 0.0
        elif t < self.duration:
            r = self.duration - t
            s, sv, sa = self.length - 0.5 * a * r * r, a * r, -a
        else:
            s, sv, sa = self.length, 0.0, 0.0
        ux, uy, uz = self.u
        p0 = self.p0
        sp[0] = p0[0] + s * ux
        sp[1] = p0[1] + s * uy
        sp[2] = p0[2] + s * uz
        sp[3] = sv * ux
        sp[4] = sv * uy
        sp[5] = sv * uz
        sp[6] = sa * ux
        sp[7] = sa * uy
        sp[8] = sa * uz


class Path:
    """Legs flown one after another; ``fill`` returns True once the last leg ends."""

    def __init__(self, legs):
        self.legs = list(legs)
        self.starts = []
        t = 0.0
        for leg in self.legs:
            self.starts.append(t)
            t += leg.duration
        self.duration = t
        self.length = sum(leg.length for leg in self.legs)
        self._i = 0

    @property
    def leg(self) -> int:
        """Index of the leg being flown (the last one ``fill`` reached)."""
        return self._i

    def fill(self, t: float, sp) -> bool:
        legs, starts = self.legs, self.starts
        i = self._i
        n = len(legs)
        while i + 1 < n and t >= starts[i + 1]:
            i += 1
        self._i = i
        legs[i].fill(t - starts[i], sp)
        return t >= self.duration


def waypoint_path(start, points, speed, accel) -> Path:
    legs = []
    prev = tuple(start)
    for p in points:
        legs.append(Leg(prev, p, speed, accel))
        prev = tuple(p)
    return Path(legs)
