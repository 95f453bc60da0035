"""Pilots: flight plans as setpoints over simulated time.

A pilot implements ``start(t, position, accel)`` (called once the drone has
taken off to ``altitude``), ``update(t, state, sp) -> done`` (write the
setpoint ``sp`` = [px py pz vx vy vz ax ay az yaw] for time t; return True when
the plan is complete) and ``to_dict()``. ``state`` is the (possibly estimated)
position and velocity ``(x, y, z, vx, vy, vz)``. When a pilot is done the
mission returns home (if asked) and lands.

Write your own by subclassing ``Pilot``; the built-ins fly time-parameterized
paths with trapezoidal speed profiles, so the controller gets position,
velocity and acceleration feed-forward.
"""

from __future__ import annotations

import functools
import inspect
import math
from collections.abc import Iterable, Sequence
from typing import Any

from .. import _check, limits
from ..errors import ConfigError, close_matches
from .trajectory import Leg, Path, waypoint_path

__all__ = ["Pilot", "Hover", "Waypoints", "ZigZag", "Orbit"]


class Pilot:
    """Base class. ``altitude`` is the height the mission takes off to."""

    altitude: float = 10.0
    #: nominal path length in metres from the start position (None if unbounded)
    path_length: float | None = None

    def __init_subclass__(cls, **kwargs):
        """A misspelled keyword (``Hover(altitdue=5)``) is a ConfigError with a
        did-you-mean, as everywhere else, not Python's plain TypeError."""
        super().__init_subclass__(**kwargs)
        init = cls.__dict__.get("__init__")
        if init is None:
            return
        params = inspect.signature(init).parameters
        if any(p.kind is p.VAR_KEYWORD for p in params.values()):
            return
        names = [n for n, p in params.items() if n != "self" and p.kind is not p.VAR_POSITIONAL]

        @functools.wraps(init)
        def checked(self, *args, **kw):
            for key in kw:
                if key not in names:
                    raise ConfigError(f"{cls.__name__}: unknown argument {key!r}"
                                      f"{close_matches(key, names)}; allowed: {', '.join(names)}")
            return init(self, *args, **kw)
        cls.__init__ = checked

    def start(self, t: float, position, accel: float) -> None:
        """The plan begins at simulated time ``t`` from ``position`` (x, y, z);
        ``accel``: the drone's acceleration limit (m/s^2)."""
        self.t0 = t

    def update(self, t: float, state, sp) -> bool:  # pragma: no cover - interface
        """Write the setpoint for time ``t`` into ``sp`` (position, velocity,
        acceleration, yaw); True when the plan is done."""
        raise NotImplementedError

    def to_dict(self) -> dict:
        """JSON-ready description for the flight's scenario."""
        return {"type": type(self).__name__}

    def __repr__(self):
        args = ", ".join(f"{k}={v!r}" for k, v in self.to_dict().items() if k != "type")
        return f"{type(self).__name__}({args})"


def _alt(value, who):
    return _extent("altitude", _check.positive("altitude", value, where=who), who)


def _extent(field, value, who):
    """A coordinate no farther from home than ``limits.MAX_EXTENT_M``."""
    limits.check_at_most(field, abs(value), "MAX_EXTENT_M", where=who, unit=" m")
    return value


def _speed(value, who):
    v = _check.positive("speed", value, where=who)
    limits.check_at_most("speed", v, "MAX_SPEED_MPS", where=who, unit=" m/s")
    return v


class Hover(Pilot):
    """Hold position over the take-off point at ``altitude`` for ``duration``
    seconds (None: until the mission ends)."""

    def __init__(self, altitude: float = 10.0, duration: float | None = None, *,
                 yaw: float = 0.0) -> None:
        self.altitude = _alt(altitude, "Hover")
        self.duration = None if duration is None else _check.non_negative("duration", duration, where="Hover")
        self.yaw = _check.number("yaw", yaw, where="Hover")
        self.path_length = 0.0

    def start(self, t: float, position, accel: float) -> None:
        self.t0 = t
        self.pos = (position[0], position[1], self.altitude)

    def update(self, t: float, state, sp) -> bool:
        sp[0], sp[1], sp[2] = self.pos
        sp[3] = sp[4] = sp[5] = sp[6] = sp[7] = sp[8] = 0.0
        sp[9] = self.yaw
        return self.duration is not None and t - self.t0 >= self.duration

    def to_dict(self) -> dict:
        return {"type": "Hover", "altitude": self.altitude, "duration": self.duration, "yaw": self.yaw}


class Waypoints(Pilot):
    """Fly through ``points`` [(x, y, z), ...] at ``speed`` m/s, stopping at each
    (trapezoidal speed profile). ``loop``: start over at the first point forever."""

    def __init__(self, points: Iterable[Sequence[float]], speed: float = 6.94, loop: bool = False,
                 *, yaw: float = 0.0) -> None:
        try:
            pts = [tuple(p) for p in points]
        except TypeError:
            raise ConfigError(f"Waypoints: points = {points!r} is not a list of (x, y, z)") from None
        if not pts:
            raise ConfigError("Waypoints: points = [] is empty; give at least one (x, y, z)")
        limits.check_at_most("len(points)", len(pts), "MAX_WAYPOINTS", where="Waypoints")
        self.points = [_check.vector(f"points[{i}]", p, 3, where="Waypoints") for i, p in enumerate(pts)]
        for i, p in enumerate(self.points):
            for axis, c in zip("xyz", p):
                _extent(f"points[{i}] {axis}", c, "Waypoints")
        for i, p in enumerate(self.points):
            if p[2] <= 0:
                raise ConfigError(f"Waypoints: points[{i}] altitude z = {p[2]!r} is not allowed; must be > 0")
        self.speed = _speed(speed, "Waypoints")
        if not isinstance(loop, bool):
            raise ConfigError(f"Waypoints: loop = {loop!r} is not allowed; expected True or False")
        self.loop = loop
        self.yaw = _check.number("yaw", yaw, where="Waypoints")
        self.altitude = self.points[0][2]
        self.path_length = sum(math.dist(a, b) for a, b in zip(self.points, self.points[1:]))

    def start(self, t: float, position, accel: float) -> None:
        self.t0 = t
        self._accel = accel
        self.path = waypoint_path(position, self.points, self.speed, accel)
        self.path_length = self.path.length

    def update(self, t: float, state, sp) -> bool:
        done = self.path.fill(t - self.t0, sp)
        sp[9] = self.yaw
        if done and self.loop:
            self.t0 = t
            self.path = waypoint_path(self.points[-1], self.points, self.speed, self._accel)
            return False
        return done

    def to_dict(self) -> dict:
        return {"type": "Waypoints", "points": [list(p) for p in self.points], "speed": self.speed,
                "loop": self.loop, "yaw": self.yaw}


class ZigZag(Waypoints):
    """Boustrophedon coverage of the box ``area`` = ((x0, y0), (x1, y1)) at
    ``altitude``: legs along x, ``spacing`` metres apart (the paper's Bounding
    Box ZigZag Pilot)."""

    def __init__(self, area: Any, altitude: float = 30.0, spacing: float = 15.0,
                 speed: float = 8.0, *, yaw: float = 0.0) -> None:
        x0, y0, x1, y1 = _check.area(area, where="ZigZag")
        for n, v in (("area x0", x0), ("area y0", y0), ("area x1", x1), ("area y1", y1)):
            _extent(n, v, "ZigZag")
        self.area = ((x0, y0), (x1, y1))
        alt = _alt(altitude, "ZigZag")
        self.spacing = _check.positive("spacing", spacing, where="ZigZag")
        points = 2 * (abs(y1 - y0) / self.spacing + 2)    # checked before any leg is built
        limits.check_at_most(f"points (2 per leg, |y1 - y0| / spacing = {abs(y1 - y0):g} m / "
                             f"{self.spacing:g} m legs)", points, "MAX_WAYPOINTS",
                             where="ZigZag", how="give a larger spacing")
        ys = []
        yy = y0
        step = self.spacing if y1 > y0 else -self.spacing
        while (y1 - yy) * step > 1e-9:
            ys.append(yy)
            yy += step
        ys.append(y1)
        pts = []
        for k, row in enumerate(ys):
            a, b = (x0, x1) if k % 2 == 0 else (x1, x0)
            pts += [(a, row, alt), (b, row, alt)]
        super().__init__(pts, speed, False, yaw=yaw)
        self.altitude = alt

    def to_dict(self) -> dict:
        return {"type": "ZigZag", "area": [list(self.area[0]), list(self.area[1])],
                "altitude": self.altitude, "spacing": self.spacing, "speed": self.speed, "yaw": self.yaw}


class Orbit(Pilot):
    """Circle ``center`` = (x, y) at ``radius`` and ``altitude``, counter-clockwise at
    ``speed`` m/s; ``laps`` turns (None: until the mission ends)."""

    def __init__(self, center: Sequence[float] = (0.0, 0.0), radius: float = 20.0,
                 altitude: float = 30.0, speed: float = 5.0, *,
                 laps: float | None = None) -> None:
        self.center = _check.vector("center", center, 2, where="Orbit")
        for axis, c in zip("xy", self.center):
            _extent(f"center {axis}", c, "Orbit")
        self.radius = _extent("radius", _check.positive("radius", radius, where="Orbit"), "Orbit")
        self.altitude = _alt(altitude, "Orbit")
        self.speed = _speed(speed, "Orbit")
        self.laps = None if laps is None else _check.positive("laps", laps, where="Orbit")
        self.path_length = None if laps is None else 2 * math.pi * self.radius * self.laps

    def start(self, t: float, position, accel: float) -> None:
        self.t0 = t
        cx, cy = self.center
        self._entry = Path([Leg(position, (cx + self.radius, cy, self.altitude), self.speed, accel)])
        # spin up along the circle with the same acceleration limit
        a_t = min(accel, self.speed ** 2 / self.radius)
        self._spin = self.speed / a_t
        self._a_t = a_t
        if self.laps is not None:
            self.path_length = self._entry.length + 2 * math.pi * self.radius * self.laps

    def update(self, t: float, state, sp) -> bool:
        tl = t - self.t0
        e = self._entry
        if tl < e.duration:
            e.fill(tl, sp)
            sp[9] = 0.0
            return False
        tc = tl - e.duration
        a_t, ts, v = self._a_t, self._spin, self.speed
        if tc < ts:
            s, sv, sa = 0.5 * a_t * tc * tc, a_t * tc, a_t
        else:
            s, sv, sa = 0.5 * a_t * ts * ts + v * (tc - ts), v, 0.0
        r = self.radius
        th = s / r
        c, sn = math.cos(th), math.sin(th)
        cx, cy = self.center
        sp[0], sp[1], sp[2] = cx + r * c, cy + r * sn, self.altitude
        sp[3], sp[4], sp[5] = -sv * sn, sv * c, 0.0
        ac = sv * sv / r  # centripetal
        sp[6], sp[7], sp[8] = -sa * sn - ac * c, sa * c - ac * sn, 0.0
        sp[9] = 0.0
        return self.laps is not None and s >= 2 * math.pi * r * self.laps

    def to_dict(self) -> dict:
        return {"type": "Orbit", "center": list(self.center), "radius": self.radius,
                "altitude": self.altitude, "speed": self.speed, "laps": self.laps}
