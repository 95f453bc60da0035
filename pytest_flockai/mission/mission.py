"""Mission: drones, pilots, a world and tasks, flown on one simulated clock.

``Mission(...)`` validates its inputs and resolves them into a flight plan at
once (every ``ConfigError`` is raised here, before anything flies);
``run()`` builds the flight, a flight of one drone (``assemble.Flight``), flies
it (``loop.fly``) and returns the ``FlightResult`` (``collect.flight_result``).
It also hands the result to the recording sink of the current context
(``pytest_flockai.recording``), so the pytest plugin sees every flight flown
inside a test, also one that ended in a ``SimulationError`` (then with the
partial result).
"""

from __future__ import annotations

import os
import time as _time

import numpy as np

from .. import _check
from .. import cache as _cache
from .. import limits
from ..airframe.drone import Drone
from ..control.pilots import Pilot
from ..errors import ConfigError, SimulationError
from ..probes.hub import resolve_probes
from ..recording import publish
from ..result import FlightResult
from ..sensors import Conditions
from ..world import World
from ..world.actors import check_actors
from ..world.wind import Wind
from . import collect, loop
from .assemble import Flight
from .plan import (check_components, check_policies, check_sensors, check_tasks, check_until,
                   resolve)
from .plan import computers as _computers


class Mission:
    """A flight to simulate: ``Mission(drone, pilot, ...).run() -> FlightResult``.

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

    def __init__(self, drone: Drone, pilot: Pilot, world=None, tasks=(), probes=None, wind=None,
                 seed: int = 0, until="landed", *, return_home: bool = True,
                 max_time_s: float = 4 * 3600.0, telemetry_hz: float = 10.0,
                 energy_hz: float = 20.0, sensors=(), fly_on: str = "truth",
                 dataset_dir=None, dataset_period_s: float = 1.0,
                 climb_speed: float = 2.0, descent_speed: float = 1.0, name: str | None = None,
                 components=(), conditions: Conditions | None = None, atmosphere=None,
                 max_wall_s: float | None = None, policies=(), actors=()):
        if not isinstance(drone, Drone):
            raise ConfigError(f"Mission: drone = {drone!r} is not a Drone; use fa.drone(name)")
        if not isinstance(pilot, Pilot):
            raise ConfigError(f"Mission: pilot = {pilot!r} is not a Pilot (fa.pilots.Hover, "
                              f"Waypoints, ZigZag, Orbit or a Pilot subclass)")
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise ConfigError(f"Mission: seed = {seed!r} is not allowed; expected an integer >= 0")
        if name is not None and (not isinstance(name, str) or not name.strip()):
            raise ConfigError(f"Mission: name = {name!r} is not allowed; expected a non-empty str")
        if world is not None and not isinstance(world, World):
            raise ConfigError(f"Mission: world = {world!r} is not allowed; expected None or a "
                              f"fa.World (World.urban(...), World.scene(...), World.from_mjcf(...))")
        if not isinstance(return_home, (bool, np.bool_)):
            raise ConfigError(f"Mission: return_home = {return_home!r} is not allowed; expected "
                              f"True or False")
        if dataset_dir is not None and not isinstance(dataset_dir, (str, os.PathLike)):
            raise ConfigError(f"Mission: dataset_dir = {dataset_dir!r} is not allowed; expected "
                              f"None or a folder path")
        self.drone, self.pilot, self.world = drone, pilot, world
        self.until = check_until(until)
        self.sensors = list(check_sensors(sensors))
        self.tasks = check_tasks(tasks, drone, self.sensors)
        self.components = list(check_components(components))
        self.probes = resolve_probes(probes)
        self.subscribers: list = []
        self.wind = Wind.coerce(wind)
        self.seed = int(seed)
        self.return_home = bool(return_home)
        self.max_time_s = _check.positive("max_time_s", max_time_s, where="Mission")
        self.telemetry_hz = _check.positive("telemetry_hz", telemetry_hz, where="Mission")
        self.energy_hz = _check.positive("energy_hz", energy_hz, where="Mission")
        limits.check_at_least("energy_hz", self.energy_hz, "MIN_ENERGY_HZ", where="Mission",
                              unit=" Hz", how="slower sampling misses the power's changes")
        self.climb_speed = _check.positive("climb_speed", climb_speed, where="Mission")
        self.descent_speed = _check.positive("descent_speed", descent_speed, where="Mission")
        for field, v in (("climb_speed", self.climb_speed), ("descent_speed", self.descent_speed)):
            limits.check_at_least(field, v, "MIN_VERTICAL_SPEED_MPS", where="Mission",
                                  unit=" m/s")
        self.name = name
        self.fly_on = _check.choice("fly_on", fly_on, ("truth", "estimate"), where="Mission")
        self.dataset_dir = dataset_dir
        self.dataset_period_s = _check.positive("dataset_period_s", dataset_period_s, where="Mission")
        if conditions is not None and not isinstance(conditions, Conditions):
            raise ConfigError(f"Mission: conditions = {conditions!r} is not allowed; expected "
                              f"fa.Conditions(...) or None")
        self.conditions = conditions
        self.atmosphere = atmosphere
        self.max_wall_s = (None if max_wall_s is None
                           else _check.positive("max_wall_s", max_wall_s, where="Mission"))
        self.actors = check_actors(actors, world)
        self.policies = check_policies(policies, self)
        resolve(self)

    def subscribe(self, target) -> "Mission":
        """Receive probe samples live: ``target`` is a callable ``fn(sample)`` or a
        ``queue.Queue``; each sample is ``{"t": s, "probe": name, "values": {...}}``."""
        if not (callable(target) or hasattr(target, "put_nowait")):
            raise ConfigError(f"Mission.subscribe: {target!r} is neither callable nor a queue")
        self.subscribers.append(target)
        return self

    def scenario(self) -> dict:
        return {
            "name": self.name, "drone": self.drone.to_dict(), "pilot": self.pilot.to_dict(),
            "world": self.world.to_dict() if self.world is not None else {"name": "empty"},
            "wind": self.wind.to_dict() if self.wind is not None else None,
            "seed": self.seed, "until": self.until, "return_home": self.return_home,
            "tasks": [getattr(t, "to_dict", lambda: repr(t))() for t in self.tasks],
            "computers": _computers(self.tasks, self.drone),
            "probes": [p.to_dict() for p in self.probes],
            "sensors": [sn.name for sn in self.drone.extra_sensors + self.sensors],
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
        found = _cache.lookup(self)     # the flight cache of this context, if one is open
        if found is not None and found.result is not None:
            publish(found.result, self)
            return found.result
        wall0 = _time.perf_counter()
        flight = Flight([resolve(self)], [self])
        run = flight.runs[0]
        try:
            loop.fly(flight)
        except SimulationError as exc:
            exc.result = collect.flight_result(run, self, _time.perf_counter() - wall0,
                                               run.data.time, getattr(exc, "end_reason", "diverged"))
            publish(exc.result, self)
            raise
        res = collect.flight_result(run, self, _time.perf_counter() - wall0, run.t_end,
                                    run.vehicle.end_reason)
        if found is not None and found.status != "off":
            found.store(res)            # before publish: derived KPIs of a test stay out
        publish(res, self)
        return res
