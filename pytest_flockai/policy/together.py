"""A fleet that searches together, through one ground station (the paper's future work,
in its simplest useful form).

Every drone of a ``fa.Fleet`` flies its own strip with a detection task and a
``SharedSearch(task, station)`` policy; all of them hold the same ``GroundStation``.
A drone whose tracker confirms a target it has not reported sends the point to the
station (``report_bytes`` up the shared radio channel: one message at a time, timed
by the link model at the drone's distance). When a report reaches the station and
the point is new (farther than ``gate_m`` from every known target), the station
assigns the nearest free drone (by the positions the drones last sent) to confirm
it; the assignment reaches that drone after the downlink. The assigned drone leaves
its strip, orbits the point for ``orbit_s``, and confirms the target when its own
detector sees it there (another message up); then it resumes its strip where it
left it. The other drones keep flying their strips (they do not re-plan them to
cover the assigned drone's: not built).

Fleet KPIs (scored against the truth after the flight): ``fleet.targets_found``
(distinct people within 5 m of a confirmed target), ``fleet.time_to_find_all_s``
(first plan start to the last confirmation reaching the station; NaN unless all
were found), ``fleet.reports``, ``fleet.assignments``; per drone (prefixed with its
name) ``policy.<name>.time_confirm_s``.
"""

from __future__ import annotations

import math

import numpy as np

from .. import _check
from ..comm.link import link as _link
from ..errors import ConfigError
from .follow import _Perceiving
from .scoring import MATCH_M


class GroundStation:
    """The fleet's ground station (see the module docstring): ``position`` (x, y, z),
    the ``link`` its radio speaks, ``report_bytes`` per message, ``gate_m``."""

    def __init__(self, position=(0.0, 0.0, 0.0), *, link="wifi-80211n", report_bytes: int = 64,
                 gate_m: float = 10.0, seed: int = 0):
        self.position = _check.vector("position", position, 3, where="GroundStation")
        try:
            self.link = _link(link)
        except ConfigError as e:
            raise ConfigError(f"GroundStation: {e}") from None
        if isinstance(report_bytes, bool) or not isinstance(report_bytes, int) or report_bytes < 1:
            raise ConfigError(f"GroundStation: report_bytes = {report_bytes!r} is not allowed; "
                              f"expected an int >= 1")
        self.report_bytes = report_bytes
        self.gate_m = _check.positive("gate_m", gate_m, where="GroundStation")
        self.seed = int(seed)
        self._flight = None

    # -- per flight ------------------------------------------------------------
    def bind_flight(self, run) -> None:
        """A drone's policy joins; the first of a new flight resets the station."""
        flight = getattr(run, "shared", run.data)
        if self._flight is not flight:
            self._flight = flight
            self.rng = np.random.default_rng(np.random.SeedSequence(self.seed, spawn_key=(27,)))
            self.channel_free = -math.inf
            self.inbox: list = []           # (t arrives, seq, kind, who, payload)
            self.outbox: list = []          # (t arrives at the drone, who, target index)
            self.targets: list = []         # [x, y, t reported, who confirmed, t confirmed]
            self.where: dict = {}           # drone -> (x, y) it last sent
            self.busy: set = set()
            self.reports = self.assignments = 0
            self._seq = 0
            self.actors = run.actors
            self.t_plan = math.inf

    def _send(self, t: float, xy, direction: str) -> float:
        """Arrival time of one message over the shared channel, sent at ``t``."""
        d = math.dist((xy[0], xy[1], self.position[2]), self.position)
        tr = self.link.transfer(self.report_bytes, d, self.rng, direction=direction)
        start = max(t, self.channel_free)
        self.channel_free = start + tr.seconds
        return start + tr.seconds

    def post(self, t: float, who: str, kind: str, xy, payload=None) -> None:
        """A drone sends a message (``report`` a point, ``confirm`` a target) at t."""
        self._seq += 1
        self.inbox.append((self._send(t, xy, "up"), self._seq, kind, who, (xy, payload)))

    def process(self, t: float) -> None:
        """Handle the messages that reached the station by t, in arrival order."""
        due = sorted(m for m in self.inbox if m[0] <= t)
        if not due:
            return
        self.inbox = [m for m in self.inbox if m[0] > t]
        for t_arr, _, kind, who, (xy, payload) in due:
            if kind == "report":
                self.reports += 1
                if any(math.dist(xy, tg[:2]) <= self.gate_m for tg in self.targets):
                    continue
                self.targets.append([xy[0], xy[1], t_arr, None, None])
                self._assign(t_arr, len(self.targets) - 1)
            elif kind == "confirm" and self.targets[payload][3] is None:
                self.targets[payload][3:] = [who, t_arr]

    def _assign(self, t: float, k: int) -> None:
        free = [w for w in sorted(self.where) if w not in self.busy]
        if not free:
            return
        x, y = self.targets[k][:2]
        who = min(free, key=lambda w: math.dist(self.where[w], (x, y)))
        self.busy.add(who)
        self.assignments += 1
        self.outbox.append((self._send(t, (x, y), "down"), who, k))

    def assignment(self, t: float, who: str):
        """The target index assigned to ``who`` that has reached it by t, or None."""
        for m in self.outbox:
            if m[1] == who and m[0] <= t:
                self.outbox.remove(m)
                return m[2]
        return None

    # -- scoring ---------------------------------------------------------------
    def kpis(self) -> dict:
        found: dict = {}
        people = [a for a in (self.actors.actors if self.actors is not None else ())
                  if a.kind == "person"]
        for x, y, _, who, t_conf in self.targets:
            if who is None:
                continue
            for i, a in enumerate(people):
                if math.dist(a.at(t_conf)[:2], (x, y)) <= MATCH_M and i not in found:
                    found[i] = t_conf
                    break
        everyone = bool(people) and len(found) == len(people)
        return {"fleet.targets_found": float(len(found)),
                "fleet.time_to_find_all_s": (max(found.values()) - self.t_plan) if everyone
                else math.nan,
                "fleet.reports": float(self.reports), "fleet.assignments": float(self.assignments)}

    def to_dict(self) -> dict:
        return {"type": "GroundStation", "position": list(self.position), "link": self.link.name,
                "report_bytes": self.report_bytes, "gate_m": self.gate_m, "seed": self.seed}


class SharedSearch(_Perceiving):
    """One drone's part in a search together (module docstring)."""

    modes = ("search", "confirm")

    def __init__(self, task: str, station: GroundStation, *, target: str = "person",
                 radius: float = 8.0, speed: float = 3.0, orbit_s: float = 20.0, confirm: int = 2,
                 name: str = "team", period_s: float = 0.2):
        super().__init__(task, target, name, period_s, station.gate_m if isinstance(
            station, GroundStation) else 10.0, confirm, None)
        if not isinstance(station, GroundStation):
            raise ConfigError(f"policy {self.name!r}: station = {station!r} is not a "
                              f"fa.policy.GroundStation")
        where = f"policy {self.name!r}"
        self.station = station
        self.radius = _check.positive("radius", radius, where=where)
        self.speed = _check.positive("speed", speed, where=where)
        self.orbit_s = _check.positive("orbit_s", orbit_s, where=where)

    def start(self, run) -> None:
        super().start(run)
        self.me = run.vehicle.name
        self.station.bind_flight(run)
        self._sent: list = []          # points this drone reported
        self._job = None               # (target index, (x, y), t started)

    def decide(self, t, drone) -> None:
        s = self.station
        s.process(t)
        if drone.stage == "pilot":
            s.t_plan = min(s.t_plan, t)
        s.where[self.me] = drone.position[:2]
        for t_cap, pts in self.measurements(drone):
            self.fuse(t_cap, pts, drone)
        if self._mode is None:
            drone.mode("search")
        tr = self.tracker
        if tr.confirmed:
            xy = tr.predict(t)[:2]
            tr.reset()
            job = self._job
            if job is not None and math.dist(xy, job[1]) <= s.gate_m:
                s.post(t, self.me, "confirm", xy, job[0])
            elif all(math.dist(xy, p) > s.gate_m for p in self._sent):
                self._sent.append(xy)
                s.post(t, self.me, "report", xy)
        elif tr.x is not None and t - tr.last_hit > 3.0:
            tr.reset()
        k = s.assignment(t, self.me) if self._job is None else None
        if k is not None and drone.orbit(*s.targets[k][:2], self.radius, self.speed):
            self._job = (k, tuple(s.targets[k][:2]), t)
            drone.mode("confirm")
        elif self._job is not None and t - self._job[2] >= self.orbit_s:
            s.busy.discard(self.me)
            self._job = None
            drone.resume()
            drone.mode("search")

    def to_dict(self):
        return {**super().to_dict(), "task": self.task, "station": self.station.to_dict(),
                "radius": self.radius, "orbit_s": self.orbit_s}


def stations(runs) -> list:
    """The distinct ground stations of the policies of ``runs`` (a fleet's drones)."""
    out: dict = {}
    for r in runs:
        for p in getattr(r, "policies", ()):
            st = getattr(p, "station", None)
            if isinstance(st, GroundStation):
                out[id(st)] = st
    return list(out.values())


__all__ = ["GroundStation", "SharedSearch", "stations"]
