"""Sensors: the interface, custom sensors and the suite the mission loop polls.

A sensor has a ``name``, a ``rate_hz`` (readings per simulated second) and a
``power_w`` (electrical power drawn while it is on: the whole flight; the
energy model reads it). Its life in a mission:

1. ``add_to_spec(spec, body_name="drone")`` once, while the model is composed
   (after ``build_spec``): a sensor may add what it needs (the camera adds a
   named MuJoCo camera); most add nothing.
2. ``bind(model, data, rng)`` once, after the model is compiled and before the
   flight: find the drone body, keep the rng (a ``numpy.random.Generator``
   from the mission seed). Every random draw of a sensor comes from this rng.
3. ``read(t, data) -> value`` whenever a reading is due (or asked for):
   a float, a numpy array or a frame.

``SensorSuite`` does the scheduling: ``suite.step(t, data)`` once per control
tick costs one float comparison when nothing is due; due sensors are read and
their value kept in ``suite.latest[name]``; ``suite.counts[name]`` counts the
readings. Sensors flagged ``on_demand`` (cameras) are never read by ``step``:
whoever needs a frame calls ``suite.read(name, t, data)`` (or the camera's
``read``), so frames are rendered only when asked for.

A sensor cannot be read more often than the loop calls ``step``: a 200 Hz IMU
in a 100 Hz control loop gives 100 readings per second (one per tick).
"""

from __future__ import annotations

import inspect
import math
import zlib
from numbers import Integral
from typing import Any

import numpy as np

from .. import _check
from ..clock import Clocked
from ..errors import ConfigError, close_matches

_EPS = 1e-9       # s: a reading due at t fires at t - eps (float time from MuJoCo)


class Sensor:
    """Base class: subclass and implement ``read(t, data)``.

    Subclasses call ``super().__init__(name, rate_hz=..., power_w=...)``;
    ``bind`` keeps ``self.model``, ``self.data``, ``self.rng``.
    """

    #: never read by ``SensorSuite.step`` (frames are rendered only on request)
    on_demand = False

    def __init__(self, name: str, *, rate_hz: float = 1.0, power_w: float = 0.0):
        where = type(self).__name__
        if not isinstance(name, str) or not name or name.strip() != name:
            raise ConfigError(f"{where}: name = {name!r} is not allowed; expected a non-empty "
                              f"string without surrounding spaces")
        self.name = name
        self.rate_hz = _check.positive("rate_hz", rate_hz, where=f"{where} {name!r}")
        self.power_w = _check.non_negative("power_w", power_w, where=f"{where} {name!r}")
        self.model: Any = None          # MuJoCo's model and data, and the noise: set by bind
        self.data: Any = None
        self.rng: np.random.Generator | None = None

    @property
    def period_s(self) -> float:
        """Seconds between readings (1 / rate_hz)."""
        return 1.0 / self.rate_hz

    def add_to_spec(self, spec, body_name: str = "drone") -> None:
        """Add what the sensor needs to the mission's MjSpec (default: nothing)."""

    def bind(self, model, data, rng: np.random.Generator) -> None:
        """Per flight: MuJoCo's model and data, and this sensor's own noise stream."""
        if not isinstance(rng, np.random.Generator):
            raise ConfigError(f"{type(self).__name__} {self.name!r}: bind(rng = {rng!r}) is not "
                              f"allowed; expected a numpy.random.Generator")
        self.model, self.data, self.rng = model, data, rng

    def read(self, t: float, data):
        """One reading at simulated time ``t`` from MuJoCo's ``data`` (override)."""
        raise NotImplementedError(f"{type(self).__name__} must implement read(t, data)")

    def to_dict(self) -> dict:
        """JSON-ready description for the flight's scenario."""
        return {"name": self.name, "type": type(self).__name__, "rate_hz": self.rate_hz,
                "power_w": self.power_w}

    def __repr__(self):
        return f"{type(self).__name__}({self.name!r}, rate_hz={self.rate_hz:g})"


class FunctionSensor(Sensor):
    """A sensor from a function: ``fn(t, data, rng) -> value`` (or ``fn(t, data)``).

    The function gets the mission's rng as a keyword if it accepts three
    arguments; draw any noise from it to stay deterministic.
    """

    def __init__(self, name: str, fn, rate_hz: float = 1.0, *, power_w: float = 0.0):
        super().__init__(name, rate_hz=rate_hz, power_w=power_w)
        if not callable(fn):
            raise ConfigError(f"FunctionSensor {name!r}: fn = {fn!r} is not callable; expected "
                              f"fn(t, data[, rng]) -> value")
        self.fn = fn
        try:
            params = inspect.signature(fn).parameters.values()
            n = sum(p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD) for p in params)
            var = any(p.kind == p.VAR_POSITIONAL for p in params)
        except (TypeError, ValueError):
            n, var = 2, False
        self._with_rng = var or n >= 3

    def read(self, t, data):
        if self._with_rng:
            return self.fn(t, data, self.rng)
        return self.fn(t, data)


class DroneBody:
    """Where a drone's state lives in MjData: body id and free-joint addresses."""

    def __init__(self, model, body_name: str, who: str):
        try:
            self.id = model.body(body_name).id
        except KeyError:
            raise ConfigError(f"{who}: body_name = {body_name!r} is not a body of the model; "
                              f"allowed: {[model.body(i).name for i in range(1, model.nbody)]}") \
                from None
        jnt = model.body_jntadr[self.id]
        if jnt < 0 or model.jnt_type[jnt] != 0:     # mjJNT_FREE
            raise ConfigError(f"{who}: body {body_name!r} has no free joint; expected the drone")
        self.qpos = int(model.jnt_qposadr[jnt])
        self.qvel = int(model.jnt_dofadr[jnt])


def _child_seed(seed, name: str) -> np.random.SeedSequence:
    """A sensor's SeedSequence keyed by its name: adding a sensor never changes another's noise."""
    key = zlib.crc32(name.encode("utf-8"))
    if isinstance(seed, np.random.Generator):
        seed = seed.bit_generator.seed_seq
    if isinstance(seed, np.random.SeedSequence):
        return np.random.SeedSequence(seed.entropy, spawn_key=tuple(seed.spawn_key) + (key,))
    if isinstance(seed, Integral) and not isinstance(seed, bool) and int(seed) >= 0:
        return np.random.SeedSequence(int(seed), spawn_key=(key,))
    raise ConfigError(f"SensorSuite.bind: seed = {seed!r} is not allowed; expected a "
                      f"numpy SeedSequence, Generator or an integer >= 0")


class SensorSuite:
    """The drone's sensors, polled by the mission loop once per control tick.

    ``step(t, data)``: reads every non-on-demand sensor that is due;
    ``read(name, t, data)``: reads one now (cameras); ``latest[name]``: the last
    value; ``counts[name]``: readings so far; ``power_w``: the sum of the
    sensors' power.
    """

    def __init__(self, sensors=()):
        items = list(sensors or ())
        names = set()
        for i, s in enumerate(items):
            if not isinstance(s, Sensor) and not _duck_sensor(s):
                raise ConfigError(f"SensorSuite: sensors[{i}] = {s!r} is not a Sensor; expected "
                                  f"GPS(), IMU(), Camera(), ... or a Sensor subclass")
            if s.name in names:
                raise ConfigError(f"SensorSuite: sensors[{i}].name = {s.name!r} is used twice; "
                                  f"sensor names must be unique")
            names.add(s.name)
        self.sensors = items
        self._by_name = {s.name: s for s in items}
        self._polled = [s for s in items if not getattr(s, "on_demand", False)]
        self._due = [0.0] * len(self._polled)
        self._next = math.inf
        self.latest: dict = {s.name: None for s in items}
        self.counts: dict = {s.name: 0 for s in items}
        self.bound = False

    # -- composition --------------------------------------------------------
    def add_to_spec(self, spec, body_name: str = "drone") -> None:
        """Let every sensor add what it needs to the mission's MjSpec."""
        for s in self.sensors:
            add = getattr(s, "add_to_spec", None)
            if add is not None:
                add(spec, body_name)

    def bind(self, model, data, seed, *, world=None, battery=None) -> None:
        """Bind every sensor; seed: the mission's sensors SeedSequence (or int / Generator).

        Each sensor gets its own Generator, keyed by its name. ``world`` is
        handed to sensors with a ``bind_world`` method (cameras, for their ground
        truth) for this flight only; nothing is assigned onto a sensor's own ``world``.
        """
        for s in self.sensors:
            if hasattr(s, "bind_world"):
                s.bind_world(world)           # this flight's world, unless the sensor has its own
            s.bind(model, data, np.random.default_rng(_child_seed(seed, s.name)))
            if battery is not None and hasattr(s, "bind_battery"):
                s.bind_battery(battery)
        t0 = float(data.time)
        self._due = [t0] * len(self._polled)
        self._next = t0 - _EPS if self._polled else math.inf
        self.latest = {s.name: None for s in self.sensors}
        self.counts = {s.name: 0 for s in self.sensors}
        self.bound = True

    # -- the loop -------------------------------------------------------------
    @property
    def next_due(self) -> float:
        """Simulated time at which the next polled sensor is due (inf if none)."""
        return self._next

    def step(self, t: float, data) -> None:
        """Read the sensors due at simulated time t; one comparison when none is."""
        if t < self._next:
            return
        self._poll(t, data)

    def _poll(self, t, data):
        due = self._due
        nxt = math.inf
        latest, counts = self.latest, self.counts
        for i, s in enumerate(self._polled):
            d = due[i]
            if t >= d - _EPS:
                latest[s.name] = s.read(t, data)
                counts[s.name] += 1
                p = 1.0 / s.rate_hz
                d += p
                if d <= t + _EPS:          # the loop is slower than the sensor: skip ahead
                    d += (math.floor((t - d) / p + _EPS) + 1) * p
                due[i] = d
            if d < nxt:
                nxt = d
        self._next = nxt - _EPS

    def read(self, name: str, t: float, data):
        """Read one sensor now (on-demand sensors: cameras); updates latest and counts."""
        s = self[name]
        v = s.read(t, data)
        self.latest[name] = v
        self.counts[name] += 1
        return v

    # -- access ---------------------------------------------------------------
    @property
    def power_w(self) -> float:
        """The sensors' power draw together (W)."""
        return float(sum(s.power_w for s in self.sensors))

    @property
    def names(self) -> list[str]:
        """The sensors' names, in order."""
        return [s.name for s in self.sensors]

    def __getitem__(self, name: str):
        try:
            return self._by_name[name]
        except KeyError:
            raise ConfigError(f"SensorSuite: sensor = {name!r} is not on the drone; allowed: "
                              f"{', '.join(map(repr, self._by_name))}"
                              f"{close_matches(name, self._by_name)}") from None

    def __contains__(self, name) -> bool:
        return name in self._by_name

    def __iter__(self):
        return iter(self.sensors)

    def __len__(self):
        return len(self.sensors)

    def to_dict(self) -> list:
        """Each sensor's description."""
        return [s.to_dict() for s in self.sensors]

    def __repr__(self):
        return f"SensorSuite({self.names})"


def _duck_sensor(s) -> bool:
    return all(hasattr(s, a) for a in ("name", "rate_hz", "power_w", "bind", "read"))


class Sensing(Clocked):
    """The polled sensors as a clocked component: reads those that are due."""

    def __init__(self, suite: SensorSuite, data):
        self.suite, self.data = suite, data
        self.next_due = suite._next

    def step(self, t: float) -> None:
        self.suite._poll(t, self.data)
        self.next_due = self.suite._next
