"""A fleet: several drones in one mission, one world, one MuJoCo model and one
simulated clock.

``Fleet([FleetDrone(...), ...], world=...).run() -> FleetResult``. Each
``FleetDrone`` has its own blueprint, pilot, tasks, seed, name and pad (where
it stands, takes off and lands). Every drone is validated as a single
``Mission`` would be (same ``ConfigError`` messages), and the fleet as a whole:
not empty, unique names, one drone per pad.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterable, Sequence
from dataclasses import KW_ONLY, dataclass
from numbers import Integral
from typing import Any, cast

from .. import _check
from ..airframe.drone import Drone
from ..control.pilots import Pilot
from ..errors import ConfigError, SimulationError
from ..mission import Mission, sortie
from ..mission.assemble import Flight
from ..mission.plan import check_tasks, resolve
from ..policy.together import stations
from ..world import World
from . import fleet_result
from . import pads as _pads
from .offload import Offload, OffloadStep, share_ground

#: m: two pads closer than this are "one pad" (a drone's footprint is < 1 m)
PAD_CLEARANCE_M = 2.0
#: at most this many drones in one fleet (the loop's cost grows with N)
MAX_DRONES = 64
#: drone names that would collide with the fleet's own KPI prefixes
RESERVED_NAMES = ("fleet", "ground", "link")


@dataclass(frozen=True, eq=False, repr=False)
class FleetDrone:
    """One drone of a fleet: ``name`` prefixes its KPIs (``drone-2.flight_time_s``)
    and names its rows in the telemetry's ``drone`` column; ``pad`` = (x, y) is
    where it stands on the ground, takes off and lands. A frozen spec like
    ``Mission``: keyword-only after the pilot, changed by ``replace`` (checked)."""

    name: str
    drone: Drone
    pilot: Pilot
    _: KW_ONLY
    pad: Sequence[float] = (0.0, 0.0)
    tasks: Iterable = ()                 # stored as a tuple of fa.Task
    seed: int = 0
    probes: Iterable | None = None
    policies: Iterable = ()              # stored as a tuple; checked by the drone's Mission

    def __post_init__(self) -> None:
        name, drone, pilot, put = self.name, self.drone, self.pilot, object.__setattr__
        if not isinstance(name, str) or not name.strip() or any(c in name for c in "./ "):
            raise ConfigError(f"FleetDrone: name = {name!r} is not allowed; expected a non-empty "
                              f"str without '.', '/' or spaces (it prefixes the drone's KPIs)")
        if name.lower() in RESERVED_NAMES:
            raise ConfigError(f"FleetDrone: name = {name!r} is not allowed; it is the prefix of "
                              f"the fleet's own KPIs ({', '.join(RESERVED_NAMES)}: "
                              f"fleet.energy_total_j, link.*, ground.*); choose another name")
        if not isinstance(drone, Drone):
            raise ConfigError(f"FleetDrone {name!r}: drone = {drone!r} is not a Drone; use "
                              f"fa.drone(name)")
        if not isinstance(pilot, Pilot):
            raise ConfigError(f"FleetDrone {name!r}: pilot = {pilot!r} is not a Pilot")
        if drone.extra_sensors:
            raise ConfigError(f"FleetDrone {name!r}: drone.add_sensor(...) sensors "
                              f"({', '.join(s.name for s in drone.extra_sensors)}) are not "
                              f"supported in a fleet yet; allowed: the blueprint's own sensors")
        seed = self.seed
        if isinstance(seed, bool) or not isinstance(seed, Integral) or seed < 0:
            raise ConfigError(f"FleetDrone {name!r}: seed = {seed!r} is not allowed; expected "
                              f"an integer >= 0")
        try:
            tasks = check_tasks(self.tasks, drone, ())      # the single Mission's checks
        except ConfigError as e:
            raise ConfigError(f"FleetDrone {name!r}: {e}") from None
        for tk in tasks:
            if tk.sensor != "camera":
                raise ConfigError(f"FleetDrone {name!r}: task {tk.name!r} reads sensor = "
                                  f"{tk.sensor!r}; in a fleet a task reads the drone's camera "
                                  f"only; allowed: sensor='camera'")
        put(self, "pad", _check.vector("pad", self.pad, 2, where=f"FleetDrone {name!r}"))
        put(self, "tasks", tuple(tasks or ()))
        put(self, "seed", int(seed))
        try:
            put(self, "policies", tuple(self.policies or ()))
        except TypeError:
            raise ConfigError(f"FleetDrone {name!r}: policies = {self.policies!r} is not a list "
                              f"of fa.Policy") from None

    def replace(self, **changes) -> FleetDrone:
        """A copy with ``changes`` (field=value), checked again like a new FleetDrone."""
        return _check.replace(self, "FleetDrone", changes)

    def to_dict(self) -> dict:
        """JSON-ready description of this drone's part of the fleet."""
        return {"name": self.name, "drone": self.drone.name, "pilot": self.pilot.to_dict(),
                "pad": list(self.pad), "seed": self.seed,
                "tasks": [tk.to_dict() for tk in self.tasks],
                **({"policies": [p.to_dict() for p in self.policies]} if self.policies else {})}

    def __repr__(self):
        return f"FleetDrone({self.name!r}, {self.drone.name!r}, pad={self.pad})"


@dataclass(frozen=True, eq=False, repr=False)
class Fleet:
    """Several drones flown together: ``Fleet(drones, *, world=None, until="landed",
    area=None, swath_m=None, ...).run() -> FleetResult``. A frozen spec like
    ``Mission``: keyword-only after the drones, changed by ``replace`` (checked).

    ``offload``: remote inference of every drone on one ground station over a
    shared (or per-drone) channel (``fa.fleet.Offload``). The drones' remote
    ``Task``s share one ground station too: one channel (``shared_link=True``;
    else one per drone) and one ground device, each a FIFO queue.
    ``area`` = ((x0, y0), (x1, y1)) and ``swath_m`` (the ground width one pass
    covers) give ``fleet.coverage_fraction``; ``until`` and ``max_time_s`` are
    the Mission's, for every drone. ``actors``: people and cars moving through the
    world, seen by every drone; each drone's ``policies`` are its own (a
    ``fa.policy.SharedSearch`` per drone with one ``GroundStation``: a search together)."""

    drones: Iterable[FleetDrone]         # stored as a tuple
    _: KW_ONLY
    world: World | None = None
    until: str | float = "landed"
    max_time_s: float = 4 * 3600.0
    telemetry_hz: float = 10.0
    area: Any = None                     # stored as ((x0, y0), (x1, y1)), sorted
    swath_m: float | None = None
    name: str | None = None
    offload: Offload | None = None
    shared_link: bool = True
    actors: Iterable = ()
    #: derived at construction: each drone's Mission, the seeds, the remote tasks
    missions: tuple = dataclasses.field(init=False, default=(), repr=False)
    seed: tuple = dataclasses.field(init=False, default=())
    remote: list = dataclasses.field(init=False, default_factory=list, repr=False)

    def __post_init__(self) -> None:
        put, drones, world = object.__setattr__, self.drones, self.world
        until, max_time_s, telemetry_hz = self.until, self.max_time_s, self.telemetry_hz
        area, swath_m, offload = self.area, self.swath_m, self.offload
        shared_link, actors = self.shared_link, self.actors
        try:
            drones = list(drones)
        except TypeError:
            raise ConfigError(f"Fleet: drones = {drones!r} is not a list of fa.FleetDrone") from None
        if not drones:
            raise ConfigError("Fleet: drones = [] is empty; allowed: 1 to "
                              f"{MAX_DRONES} fa.FleetDrone(...)")
        if len(drones) > MAX_DRONES:
            raise ConfigError(f"Fleet: {len(drones)} drones is too many; allowed: at most "
                              f"{MAX_DRONES}")
        for i, fd in enumerate(drones):
            if not isinstance(fd, FleetDrone):
                raise ConfigError(f"Fleet: drones[{i}] = {fd!r} is not a fa.FleetDrone(name, "
                                  f"drone, pilot, pad=...)")
        _check_unique(drones)
        if world is not None and not isinstance(world, World):
            raise ConfigError(f"Fleet: world = {world!r} is not allowed; expected None or a fa.World")
        _check_pads(drones, world)
        if offload is not None and not isinstance(offload, Offload):
            raise ConfigError(f"Fleet: offload = {offload!r} is not allowed; expected None or "
                              f"fa.fleet.Offload(...)")
        put(self, "drones", tuple(drones))
        if not isinstance(shared_link, bool):
            raise ConfigError(f"Fleet: shared_link = {shared_link!r} is not allowed; expected "
                              f"True or False")
        put(self, "remote", _check_remote(drones, offload))
        put(self, "area", _check_area(area))
        put(self, "swath_m", None if swath_m is None
            else _check.positive("swath_m", swath_m, where="Fleet"))
        if (self.area is None) != (self.swath_m is None):
            raise ConfigError(f"Fleet: area = {area!r} and swath_m = {swath_m!r}: give both (for "
                              f"fleet.coverage_fraction) or neither")
        put(self, "missions", tuple(
            Mission(fd.drone, fd.pilot, world=world, tasks=fd.tasks, probes=fd.probes,
                    seed=fd.seed, until=until, max_time_s=max_time_s, telemetry_hz=telemetry_hz,
                    name=fd.name, policies=fd.policies, actors=actors) for fd in drones))
        put(self, "actors", self.missions[0].actors)
        put(self, "seed", tuple(fd.seed for fd in drones))
        self._plans()

    def taken_from_cache(self, result) -> None:
        """The flight cache answered ``result``: each ground station of a search together
        is left as flying the fleet left it (``GroundStation.record``)."""
        for st, rec in zip(stations(self.missions), getattr(result, "stations", ())):
            st.restore(rec)

    def replace(self, **changes) -> Fleet:
        """A copy with ``changes`` (field=value), checked again like a new Fleet."""
        return _check.replace(self, "Fleet", changes)

    def _plans(self) -> list:
        plans = [resolve(m) for m in self.missions]
        dts = {(p.physics_dt, p.substeps) for p in plans}
        if len(dts) > 1:
            raise ConfigError(f"Fleet: the drones' [sim] rates differ ({sorted(dts)} as (physics "
                              f"dt, substeps)); allowed: one physics_hz and control_hz for the "
                              f"whole fleet (one simulated clock)")
        return plans

    def scenario(self) -> dict:
        """JSON-ready description of what is flown (the drones, the world, the seed...)."""
        return {"name": self.name, "fleet": [fd.to_dict() for fd in self.drones],
                "world": self.world.to_dict() if self.world is not None else {"name": "empty"},
                "area": [list(c) for c in self.area] if self.area else None,
                "swath_m": self.swath_m,
                "offload": self.offload.to_dict() if self.offload is not None else None,
                "shared_link": self.shared_link}

    def __repr__(self):
        return f"Fleet({[fd.name for fd in self.drones]!r})"

    def run(self) -> fleet_result.FleetResult:
        """Fly every drone together (or take the fleet from the open flight cache); a
        ``SimulationError`` carries the partial FleetResult on ``.result``."""
        return cast(fleet_result.FleetResult, sortie.run(self, _AllDrones, fleet_result.FleetResult))


class _AllDrones:
    """A Fleet's sortie (``mission.sortie.run``): every drone in one flight, the fleet-wide
    steps (offload, separation) after the drones' components, and its FleetResult."""

    def __init__(self, fleet: Fleet) -> None:
        self.fleet = fleet
        self.flight = Flight(fleet._plans(), fleet.missions, [fd.name for fd in fleet.drones],
                             [fd.pad for fd in fleet.drones])
        runs = self.flight.runs
        self.off = OffloadStep(fleet.offload, runs) if fleet.offload is not None else None
        self.sep = fleet_result.Separation()
        self.ground = share_ground(runs, fleet.shared_link) if fleet.remote else None
        self.steps: Sequence = [st for st in (self.off, self.sep) if st is not None]

    def finished(self, wall_s: float) -> fleet_result.FleetResult:
        runs = self.flight.runs
        stats = {"min_separation_m": self.sep.min_m, "t_end": [r.t_end for r in runs],
                 "offload": self.off, "ground": self.ground}
        return fleet_result.build(self.fleet, runs, stats, wall_s)

    def stopped(self, exc: SimulationError, wall_s: float) -> fleet_result.FleetResult:
        return fleet_result.build(self.fleet, self.flight.runs, {"min_separation_m": math.inf}, wall_s)


def _check_unique(drones) -> None:
    seen: dict = {}
    for i, fd in enumerate(drones):
        if fd.name in seen:
            raise ConfigError(f"Fleet: drones[{i}].name = {fd.name!r} is also drones"
                              f"[{seen[fd.name]}].name; allowed: a unique name per drone")
        seen[fd.name] = i
    for i, a in enumerate(drones):
        for j in range(i):
            b = drones[j]
            gap = math.dist(a.pad, b.pad)
            if gap < PAD_CLEARANCE_M:
                raise ConfigError(
                    f"Fleet: drones[{i}].pad = {tuple(a.pad)} ({a.name!r}) is {gap:.2f} m from "
                    f"drones[{j}].pad = {tuple(b.pad)} ({b.name!r}); two drones at one pad; "
                    f"allowed: pads at least {PAD_CLEARANCE_M:g} m apart")


def _check_pads(drones, world) -> None:
    """A pad inside a building or against its wall: the drone could not take off."""
    obs = _pads.obstacles(world)
    for fd in drones:
        why = _pads.problem(obs, fd.pad)
        if why is not None:
            raise ConfigError(f"Fleet: drone {fd.name!r} pad = ({fd.pad[0]:g}, {fd.pad[1]:g}) is "
                              f"{why}; a drone cannot take off there: allowed: a pad on free "
                              f"ground (fa.fleet.survey(..., world=world) picks free pads)")


def _check_remote(drones, offload) -> list:
    """The fleet's remote tasks, which share one ground station: one link, one ground
    device, one station position; not beside ``offload`` (a second queue model)."""
    remote = [(fd.name, tk) for fd in drones for tk in fd.tasks if tk.execution == "remote"]
    if remote and offload is not None:
        raise ConfigError(f"Fleet: offload = {offload!r} and remote tasks ({remote[0][0]!r}: "
                          f"{remote[0][1].name!r}) together are not supported; allowed: one "
                          f"of them (the remote tasks queue on the fleet's ground station)")
    for field in ("link", "ground_device", "ground_station"):
        seen: dict[object, str] = {}
        for name, tk in remote:
            v = getattr(tk, field)
            key = getattr(v, "name", None) or tuple(v)
            seen.setdefault(key, f"{name}: {tk.name}")
        if len(seen) > 1:
            got = ", ".join(f"{who} -> {key}" for key, who in seen.items())
            raise ConfigError(f"Fleet: the remote tasks' {field} differ ({got}); allowed: one "
                              f"{field} for the fleet's one ground station")
    return remote


def _check_area(area):
    if area is None:
        return None
    x0, y0, x1, y1 = _check.area(area, where="Fleet")
    return ((min(x0, x1), min(y0, y1)), (max(x0, x1), max(y0, y1)))


__all__ = ["Fleet", "FleetDrone", "MAX_DRONES", "PAD_CLEARANCE_M"]
