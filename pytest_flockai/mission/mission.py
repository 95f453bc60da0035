"""Mission: drones, pilots, a world and tasks, flown on one simulated clock.

A ``Mission`` is a frozen spec: ``Mission(drone, pilot, *, world=..., seed=...)``
checks its inputs and resolves them into a flight plan at once (every
``ConfigError`` is raised here, before anything flies); a changed copy comes
from ``m.replace(seed=1)`` (or ``dataclasses.replace``), which checks again;
assigning a field raises ``dataclasses.FrozenInstanceError``. ``run()`` builds
the flight, a flight of one drone (``assemble.Flight``), flies it
(``loop.fly``) and returns the ``FlightResult`` (``collect.flight_result``).
It also hands the result to the recording sink of the current context
(``pytest_flockai.recording``), so the pytest plugin sees every flight flown
inside a test, also one that ended in a ``SimulationError`` (then with the
partial result).
"""

from __future__ import annotations

import os
import queue
from collections.abc import Callable, Iterable, Sequence
from dataclasses import KW_ONLY, dataclass, field

import numpy as np

from .. import _check, limits
from ..airframe.drone import Drone
from ..control.pilots import Pilot
from ..errors import ConfigError, SimulationError
from ..probes.hub import resolve_probes
from ..result import FlightResult
from ..sensors import Conditions
from ..world import Atmosphere, World
from ..world.actors import check_actors
from ..world.wind import Wind
from . import collect, sortie
from .assemble import Flight
from .plan import check_components, check_policies, check_sensors, check_tasks, check_until, resolve
from .plan import computers as _computers


class _Probes(tuple):
    """A Mission's probes once resolved (the built-in ones with the user's): a copy made
    by ``replace`` keeps them as they are instead of resolving them again."""

    __slots__ = ()


@dataclass(frozen=True, eq=False, repr=False)
class Mission:
    """A flight to simulate: ``Mission(drone, pilot, *, ...).run() -> FlightResult``.

    A frozen spec: every argument after ``drone`` and ``pilot`` is keyword-only,
    all are checked here, and ``m.replace(**changes)`` returns a checked copy.

    until: "landed" (fly the plan, return home, land), "battery_depleted" (fly
    until the battery is empty), "battery_reserve" (return home and land when the
    battery falls to its reserve), or a number of simulated seconds.
    components: your own clocked components (``fa.Clocked``), stepped every tick
    or on their own period, after the built-in ones.
    max_time_s: the cap on simulated time (default 4 h, at most
    ``limits.MAX_TIME_S``); a numeric ``until`` must not exceed it.
    max_wall_s: seconds of host time after which the flight is stopped with a
    ``SimulationError`` (``end_reason`` ``"wall_time"``) carrying the partial
    result in ``.result`` (None: no limit).
    policies: ``fa.Policy`` objects that decide during the flight from what the
    drone knows (``fa.policy``: Rule, Follow, SearchThenOrbit, your own).
    actors: people and cars moving through the world (``fa.actors.Person``, ``Car``).
    """

    drone: Drone
    pilot: Pilot
    _: KW_ONLY
    world: World | None = None
    tasks: Iterable = ()                 # stored as a tuple of fa.Task
    probes: Iterable | None = None       # stored as the resolved tuple (built-in + yours)
    wind: Wind | None = None             # also a speed along x or (x, y, z) m/s; stored as Wind
    seed: int = 0
    until: str | float = "landed"
    return_home: bool = True
    max_time_s: float = 4 * 3600.0
    telemetry_hz: float = 10.0
    energy_hz: float = 20.0
    sensors: Iterable = ()               # stored as a tuple of fa.sensors.Sensor
    fly_on: str = "truth"
    dataset_dir: str | os.PathLike | None = None
    dataset_period_s: float = 1.0
    climb_speed: float = 2.0
    descent_speed: float = 1.0
    name: str | None = None
    components: Iterable = ()            # stored as a tuple of fa.Clocked
    conditions: Conditions | None = None
    atmosphere: Atmosphere | None = None
    max_wall_s: float | None = None
    policies: Iterable = ()              # stored as a tuple of fa.Policy
    actors: Iterable = ()                # stored as a tuple of actors
    #: live probe subscribers (``subscribe``): not part of the spec, not copied by ``replace``
    subscribers: list = field(default_factory=list, init=False, compare=False)

    def __post_init__(self) -> None:
        put = object.__setattr__         # the checked, normalized value of a frozen field
        drone, pilot, seed, name = self.drone, self.pilot, self.seed, self.name
        if not isinstance(drone, Drone):
            raise ConfigError(f"Mission: drone = {drone!r} is not a Drone; use fa.drone(name)")
        if not isinstance(pilot, Pilot):
            raise ConfigError(f"Mission: pilot = {pilot!r} is not a Pilot (fa.pilots.Hover, "
                              f"Waypoints, ZigZag, Orbit or a Pilot subclass)")
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise ConfigError(f"Mission: seed = {seed!r} is not allowed; expected an integer >= 0")
        if name is not None and (not isinstance(name, str) or not name.strip()):
            raise ConfigError(f"Mission: name = {name!r} is not allowed; expected a non-empty str")
        if self.world is not None and not isinstance(self.world, World):
            raise ConfigError(f"Mission: world = {self.world!r} is not allowed; expected None or a "
                              f"fa.World (World.urban(...), World.scene(...), World.from_mjcf(...))")
        if not isinstance(self.return_home, (bool, np.bool_)):
            raise ConfigError(f"Mission: return_home = {self.return_home!r} is not allowed; "
                              f"expected True or False")
        if self.dataset_dir is not None and not isinstance(self.dataset_dir, (str, os.PathLike)):
            raise ConfigError(f"Mission: dataset_dir = {self.dataset_dir!r} is not allowed; "
                              f"expected None or a folder path")
        put(self, "until", check_until(self.until))
        put(self, "sensors", tuple(check_sensors(self.sensors)))
        put(self, "tasks", check_tasks(self.tasks, drone, self.sensors))
        put(self, "components", tuple(check_components(self.components)))
        if not isinstance(self.probes, _Probes):    # a copy keeps its resolved probes
            put(self, "probes", _Probes(resolve_probes(self.probes)))
        put(self, "wind", Wind.coerce(self.wind))
        put(self, "seed", int(seed))
        put(self, "return_home", bool(self.return_home))
        for f in ("max_time_s", "telemetry_hz", "energy_hz", "climb_speed", "descent_speed",
                  "dataset_period_s"):
            put(self, f, _check.positive(f, getattr(self, f), where="Mission"))
        limits.check_at_least("energy_hz", self.energy_hz, "MIN_ENERGY_HZ", where="Mission",
                              unit=" Hz", how="slower sampling misses the power's changes")
        for f in ("climb_speed", "descent_speed"):
            limits.check_at_least(f, getattr(self, f), "MIN_VERTICAL_SPEED_MPS", where="Mission",
                                  unit=" m/s")
        put(self, "fly_on", _check.choice("fly_on", self.fly_on, ("truth", "estimate"),
                                          where="Mission"))
        if self.conditions is not None and not isinstance(self.conditions, Conditions):
            raise ConfigError(f"Mission: conditions = {self.conditions!r} is not allowed; expected "
                              f"fa.Conditions(...) or None")
        if self.max_wall_s is not None:
            put(self, "max_wall_s", _check.positive("max_wall_s", self.max_wall_s, where="Mission"))
        put(self, "actors", check_actors(self.actors, self.world))
        put(self, "policies", check_policies(self.policies, self))
        resolve(self)

    def __getstate__(self) -> dict:
        """Pickle and copy the spec; live subscribers stay with this object."""
        return {k: v for k, v in self.__dict__.items() if k != "subscribers"}

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state, subscribers=[])

    def replace(self, **changes) -> Mission:
        """A copy with ``changes`` (field=value), checked again like a new Mission
        (``dataclasses.replace``); live subscribers are not copied."""
        return _check.replace(self, "Mission", changes)

    def subscribe(self, target: Callable[[dict], object] | queue.Queue) -> Mission:
        """Receive probe samples live: ``target`` is a callable ``fn(sample)`` or a
        ``queue.Queue``; each sample is ``{"t": s, "probe": name, "values": {...}}``."""
        if not (callable(target) or hasattr(target, "put_nowait")):
            raise ConfigError(f"Mission.subscribe: {target!r} is neither callable nor a queue")
        self.subscribers.append(target)
        return self

    def scenario(self) -> dict:
        """JSON-ready description of what is flown (drone, pilot, world, seed...)."""
        return {
            "name": self.name, "drone": self.drone.to_dict(), "pilot": self.pilot.to_dict(),
            "world": self.world.to_dict() if self.world is not None else {"name": "empty"},
            "wind": self.wind.to_dict() if self.wind is not None else None,
            "seed": self.seed, "until": self.until, "return_home": self.return_home,
            "tasks": [getattr(t, "to_dict", lambda t=t: repr(t))() for t in self.tasks],
            "computers": _computers(self.tasks, self.drone),
            "probes": [p.to_dict() for p in self.probes or ()],
            "sensors": [sn.name for sn in [*self.drone.extra_sensors, *self.sensors]],
            "fly_on": self.fly_on,
            **({"components": [c.to_dict() for c in self.components]} if self.components else {}),
            **({"conditions": self.conditions.to_dict()} if self.conditions is not None else {}),
            **({"atmosphere": self.atmosphere.to_dict()} if self.atmosphere is not None else {}),
            **({"policies": [p.to_dict() for p in self.policies]} if self.policies else {}),
            **({"actors": [a.to_dict() for a in self.actors]} if self.actors else {}),
        }

    def __repr__(self):
        return f"Mission({self.drone.name!r}, {self.pilot!r}, seed={self.seed}, until={self.until!r})"

    def run(self) -> FlightResult:
        """Fly the mission (or take it from the open flight cache) and return its
        result; a ``SimulationError`` carries the partial result on ``.result``."""
        return sortie.run(self, _OneDrone)


class _OneDrone:
    """A Mission's sortie (``sortie.run``): one drone's flight and its FlightResult."""

    def __init__(self, mission: Mission) -> None:
        self.mission = mission
        self.flight = Flight([resolve(mission)], [mission])
        self.steps: Sequence = ()

    def finished(self, wall_s: float) -> FlightResult:
        run = self.flight.runs[0]
        return collect.flight_result(run, self.mission, wall_s, run.t_end, run.vehicle.end_reason)

    def stopped(self, exc: SimulationError, wall_s: float) -> FlightResult:
        run = self.flight.runs[0]
        return collect.flight_result(run, self.mission, wall_s, run.data.time,
                                     getattr(exc, "end_reason", "diverged"))
