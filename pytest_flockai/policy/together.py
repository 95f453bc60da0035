"""A fleet that searches together, through one ground station (the paper's future work, in its
simplest useful form).

Every drone of a ``fa.Fleet`` flies its own strip with a detection task and a ``SharedSearch(task,
station)`` policy; all of them hold the same ``GroundStation``. A drone whose tracker confirms a
target it has not reported sends the point to the station (``report_bytes`` up the shared radio
channel: one message at a time, timed by the link model at the drone's distance). When a report
reaches the station and the point is new (farther than ``gate_m`` from every known target), the
station assigns the nearest free drone (by the positions the drones last sent) to confirm it; the
assignment reaches that drone after the downlink. The assigned drone leaves its strip, orbits the
point for ``orbit_s``, and confirms the target when its own detector sees it there (another message
up).

Re-planning together (``share``, default "none": every drone keeps its own strip): the diverted
drone sends the unflown part of its plan (``plan_ahead``: where it left the plan, then the
waypoints not reached) up in a ``handoff`` message. With "tail" the station cuts off the tail the
drone would have flown in its time away (``2 * distance + orbit_s * speed`` metres) and splits it
into contiguous parts, one per free drone; with "all" it splits all of it into one part per free
drone plus one that the diverted drone keeps. Each part goes to the nearest free drone not yet
given one (by the positions last sent), which appends it to its own unflown plan (``replan`` event:
``cover`` = whose legs, ``added`` = waypoints); after the orbit the diverted drone flies what the
station left it (``replan`` with ``kept``), plus any part it was given meanwhile. A target reported
while no drone is free waits for the next drone that reports itself free (``free`` message up).

Association (nearest neighbour with a gate): the station keeps each target's last fix (its report
or the last report associated with it: where and when; not a confirmation, which may be of another
person walking by; with ``predict`` also the reporting tracker's velocity, and the fix moves on
with it). A report is the same target as the nearest one whose fix lies within ``gate_m +
min(walk_mps * age, gate_max_m)`` (age: time since that fix), and only moves its fix; a report
outside every gate is a new target and gets an assignment. ``gate_m`` (10 m) covers the position
error of one fix (box noise and the nav estimate at 20 m altitude); ``walk_mps`` 1.4 m/s is a
comfortable walking pace (Bohannon 1997, Age and Ageing 26(1): 127-146 cm/s, adults 20-79), the
farthest a person is likely to have gone since the fix; ``gate_max_m`` (default 0, a fixed gate)
caps that growth: a growing gate also merges two people who pass each other
(tests/fleet/test_fleet_search.py).

Fleet KPIs (scored against the truth after the flight): ``fleet.targets_found`` (distinct people
within 5 m of a confirmed target), ``fleet.time_to_find_all_s`` (first plan start to the last
confirmation reaching the station; NaN unless all were found), ``fleet.reports``,
``fleet.assignments``, ``fleet.associations`` (reports taken as a known target),
``fleet.handoffs``; per drone (prefixed with its name) ``policy.<name>.time_confirm_s``."""

from __future__ import annotations

import math

import numpy as np

from .. import _check
from ..comm.link import link as _link
from ..errors import ConfigError
from . import handoff
from .follow import _Perceiving
from .scoring import MATCH_M

#: what a diverted drone hands to the free drones: nothing, the tail of its plan as
#: long as its time away would have flown, or all its unflown plan
SHARES = ("none", "tail", "all")


class GroundStation:
    """The fleet's ground station (see the module docstring): ``position`` (x, y, z),
    the ``link`` its radio speaks, ``report_bytes`` per message, ``gate_m``."""

    def __init__(self, position=(0.0, 0.0, 0.0), *, link="wifi-80211n", report_bytes: int = 64,
                 gate_m: float = 10.0, walk_mps: float = 1.4, gate_max_m: float = 0.0,
                 share: str = "none", predict: bool = False, seed: int = 0):
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
        self.walk_mps = _check.non_negative("walk_mps", walk_mps, where="GroundStation")
        self.gate_max_m = _check.non_negative("gate_max_m", gate_max_m, where="GroundStation")
        self.predict = bool(predict)
        self.share = _check.choice("share", share, SHARES, where="GroundStation")
        self.seed = int(seed)
        self._flight = None
        self._kpis: dict | None = None

    # -- per flight ------------------------------------------------------------
    def bind_flight(self, run) -> None:
        """A drone's policy joins; the first of a new flight resets the station."""
        flight = getattr(run, "shared", run.data)
        if self._flight is not flight:
            self._flight = flight
            self.rng = np.random.default_rng(np.random.SeedSequence(self.seed, spawn_key=(27,)))
            self.channel_free = -math.inf
            self.inbox: list = []           # (t arrives, seq, kind, who, payload)
            self.outbox: list = []          # (t arrives at the drone, seq, who, kind, payload)
            self.targets: list = []         # [x, y, t reported, who confirmed, t, x, y confirmed]
            self.fix: list = []             # per target: (x, y, t) of its last fix
            self.where: dict = {}           # drone -> (x, y) it last sent
            self.busy: set = set()
            self.waiting: list = []         # targets no drone was free to confirm yet
            self.flying: set = set()        # drones flying their plan (pilot stage)
            self.reports = self.assignments = self.associations = self.handoffs = 0
            self._seq = 0
            self.actors = run.actors
            self.t_plan = math.inf
            self._kpis = None

    def _send(self, t: float, xy, direction: str, extra: int = 0) -> float:
        """Arrival time of one message (``report_bytes`` + ``extra``) over the shared
        channel, sent at ``t``."""
        d = math.dist((xy[0], xy[1], self.position[2]), self.position)
        tr = self.link.transfer(self.report_bytes + extra, d, self.rng, direction=direction)
        start = max(t, self.channel_free)
        self.channel_free = start + tr.seconds
        return start + tr.seconds

    def post(self, t: float, who: str, kind: str, xy, payload=None) -> None:
        """A drone sends a message (``report`` a point, ``confirm`` a target, ``handoff``
        its unflown waypoints, 12 bytes each) at t."""
        self._seq += 1
        extra = 12 * len(payload[0]) if kind == "handoff" else 0
        self.inbox.append((self._send(t, xy, "up", extra), self._seq, kind, who, (xy, payload)))

    def _down(self, t: float, who: str, kind: str, payload, extra: int = 0) -> None:
        self._seq += 1
        arrive = self._send(t, self.where.get(who, self.position[:2]), "down", extra)
        self.outbox.append((arrive, self._seq, who, kind, payload))

    def process(self, t: float) -> None:
        """Handle the messages that reached the station by t, in arrival order."""
        due = sorted(m for m in self.inbox if m[0] <= t)
        if not due:
            return
        self.inbox = [m for m in self.inbox if m[0] > t]
        for t_arr, _, kind, who, (xy, payload) in due:
            if kind == "report":
                self.reports += 1
                k = self.associate(xy, t_arr)
                if k is not None:
                    self.associations += 1
                    self.fix[k] = (xy[0], xy[1], t_arr, *payload)
                    continue
                self.targets.append([xy[0], xy[1], t_arr, None, None, None, None])
                self.fix.append((xy[0], xy[1], t_arr, *payload))
                self._assign(t_arr, len(self.targets) - 1)
            elif kind == "confirm":
                k = payload
                if self.targets[k][3] is None:
                    self.targets[k][3:] = [who, t_arr, xy[0], xy[1]]
            elif kind == "handoff":
                self._split(t_arr, who, payload)
            elif kind == "free":
                self._free(t_arr, who)

    def associate(self, xy, t: float):
        """The known target a report at ``xy`` (reaching the station at t) is, or None:
        the nearest whose last fix is within ``gate_m + min(walk_mps * age, gate_max_m)``."""
        best, best_d = None, math.inf
        for k, (x, y, t_fix, vx, vy) in enumerate(self.fix):
            age = max(t - t_fix, 0.0)
            d = math.dist(xy, (x + vx * age, y + vy * age))
            if d <= self.gate_m + min(self.walk_mps * age, self.gate_max_m) \
                    and d < best_d:
                best, best_d = k, d
        return best

    def _split(self, t: float, who: str, payload) -> None:
        """Share ``who``'s unflown waypoints with the free drones (module docstring)."""
        ahead, away_m = payload
        free = [w for w in sorted(self.flying) if w not in self.busy and w != who]
        if not free or self.share == "none":
            return
        if self.share == "tail":
            head, rest = handoff.tail(ahead, away_m)
            parts = handoff.cut(rest, len(free))
        else:
            head, *parts = handoff.cut(ahead, len(free) + 1) or [[]]
        if not parts:
            return
        self.handoffs += 1
        self._down(t, who, "keep", head, 12 * len(head))
        for part in parts:
            to = min(free, key=lambda w: math.dist(self.where[w], part[0][:2]))
            free.remove(to)
            self._down(t, to, "cover", (who, part), 12 * len(part))

    def at(self, k: int, t: float) -> tuple:
        """Where target k is expected at t: its last fix moved on at its reported velocity."""
        x, y, t_fix, vx, vy = self.fix[k]
        age = max(t - t_fix, 0.0)
        return x + vx * age, y + vy * age

    def _assign(self, t: float, k: int) -> None:
        free = [w for w in sorted(self.where) if w not in self.busy]
        if not free:
            self.waiting.append(k)      # the next drone to come free takes it
            return
        who = min(free, key=lambda w: math.dist(self.where[w], self.at(k, t)))
        self._send_to(t, who, k)

    def _send_to(self, t: float, who: str, k: int) -> None:
        self.busy.add(who)
        self.assignments += 1
        self._down(t, who, "assign", (k, *self.at(k, t)))

    def _free(self, t: float, who: str) -> None:
        """``who`` finished its job: free again; it takes the waiting target nearest it."""
        self.busy.discard(who)
        if self.waiting:
            k = min(self.waiting, key=lambda j: math.dist(self.where[who], self.at(j, t)))
            self.waiting.remove(k)
            self._send_to(t, who, k)

    def deliver(self, t: float, who: str) -> list:
        """The messages for ``who`` that have reached it by t, in arrival order:
        (kind, payload) with kind ``assign`` (target index), ``keep`` (waypoints) or
        ``cover`` ((from whom, waypoints))."""
        due = sorted(m for m in self.outbox if m[2] == who and m[0] <= t)
        if due:
            self.outbox = [m for m in self.outbox if not (m[2] == who and m[0] <= t)]
        return [(m[3], m[4]) for m in due]

    # -- scoring ---------------------------------------------------------------
    def record(self) -> dict:
        """What the station holds after a flight (its targets, their last fixes, the
        counts, ``kpis()``), as JSON data: a flight cache entry carries it, so a flight
        taken from the cache leaves the station as flying it did (``restore``)."""
        return {"targets": [[v if v is None or isinstance(v, str) else float(v) for v in tg]
                             for tg in self.targets],
                "fix": [[float(v) for v in f] for f in self.fix],
                "counts": [self.reports, self.assignments, self.associations, self.handoffs],
                "t_plan": float(self.t_plan), "kpis": self.kpis()}

    def restore(self, rec: dict) -> None:
        """The state ``record`` wrote, on this station (a flight taken from the cache)."""
        self._flight, self.actors, self._kpis = None, None, dict(rec["kpis"])
        self.targets = [list(tg) for tg in rec["targets"]]
        self.fix = [tuple(f) for f in rec["fix"]]
        self.reports, self.assignments, self.associations, self.handoffs = rec["counts"]
        self.t_plan = rec["t_plan"]

    def kpis(self) -> dict:
        """Fleet KPIs: people found (a confirmed target within ``MATCH_M`` of one), the
        time to find them all after the plan started, reports and assignments."""
        if self.actors is None and self._kpis is not None:   # restored: scored when flown
            return dict(self._kpis)
        found: dict = {}
        people = [a for a in (self.actors.actors if self.actors is not None else ())
                  if a.kind == "person"]
        for _, _, _, who, t_conf, x, y in self.targets:
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
                "fleet.reports": float(self.reports), "fleet.assignments": float(self.assignments),
                "fleet.associations": float(self.associations),
                "fleet.handoffs": float(self.handoffs)}

    def to_dict(self) -> dict:
        """JSON-ready description for the scenario."""
        return {"type": "GroundStation", "position": list(self.position), "link": self.link.name,
                "report_bytes": self.report_bytes, "gate_m": self.gate_m,
                "walk_mps": self.walk_mps, "gate_max_m": self.gate_max_m, "share": self.share,
                "seed": self.seed}


class SharedSearch(_Perceiving):
    """One drone's part in a search together (module docstring)."""

    modes = ("search", "confirm")
    judges = True

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
        self._job: tuple | None = None   # (target index, (x, y), t started)
        self._todo: list = []          # assignments received, not started
        self._keep: list | None = None   # waypoints the station left this drone after a handoff
        self._extra: list = []         # waypoints given to cover while on a job

    def decide(self, t, drone) -> None:
        s = self.station
        s.process(t)
        if drone.stage == "pilot":
            s.t_plan = min(s.t_plan, t)
            s.flying.add(self.me)
        else:
            s.flying.discard(self.me)
        s.where[self.me] = drone.position[:2]
        for kind, payload in s.deliver(t, self.me):
            self._receive(t, drone, kind, payload)
        for t_cap, pts, t_del in self.measurements(drone):
            self.fuse(t_cap, pts, drone, t_del)
        if self._mode is None:
            drone.mode("search")
        tr = self.tracker
        job, new = self._job, False     # only a new target's report is judged (plausible.py)
        if tr.confirmed:
            x, y, vx, vy = tr.predict(t)
            near = job is not None and math.dist((x, y), job[1]) <= s.gate_m
            new = not near and all(math.dist((x, y), q) > s.gate_m for q in self._sent)
        if tr.confirmed and (not new or self.plausible(drone)):
            tr.reset()
            if new:
                self._sent.append((x, y))
                s.post(t, self.me, "report", (x, y), (vx, vy) if s.predict else (0.0, 0.0))
            elif near and job is not None:
                s.post(t, self.me, "confirm", (x, y), job[0])
        elif tr.x is not None and t - tr.last_delivered > self.max_age_s:
            tr.reset()
        job = self._todo.pop(0) if self._job is None and self._todo else None
        if job is not None:
            k, x, y = job
            if drone.orbit(x, y, self.radius, self.speed):
                self._job = (k, (x, y), t)
                drone.mode("confirm")
                ahead = drone.plan_ahead()
                if len(ahead) > 1:      # metres of plan the time away would have flown
                    away = math.dist(drone.position[:2], (x, y))
                    speed = getattr(drone.plan_pilot, "speed", self.speed)
                    s.post(t, self.me, "handoff", drone.position[:2],
                           (ahead, 2 * away + self.orbit_s * speed))
            else:                       # refused (outside the world or the fence)
                s.post(t, self.me, "free", drone.position[:2])
        elif self._job is not None and t - self._job[2] >= self.orbit_s:
            s.post(t, self.me, "free", drone.position[:2])
            self._job = None
            self._back(drone)
            drone.mode("search")

    def _receive(self, t, drone, kind: str, payload) -> None:
        """A message from the station reached this drone."""
        if kind == "assign":
            self._todo.append(payload)
        elif kind == "keep":
            self._keep = list(payload)
        elif kind == "cover":
            who, pts = payload
            if self._job is not None:
                self._extra += pts
            else:
                drone.replan(drone.plan_ahead() + list(pts), cover=who, added=len(pts))

    def _back(self, drone) -> None:
        """After an orbit: the waypoints kept at the handoff (or the plan as it was left),
        then those given to cover meanwhile."""
        kept = self._keep
        if kept is None and not self._extra:
            drone.resume()
            return
        route = (kept if kept is not None else drone.plan_ahead()) + self._extra
        self._keep, self._extra = None, []
        if route:
            drone.replan(route, kept=len(kept or ()))
        else:
            drone.resume()

    def to_dict(self) -> dict:
        return {**super().to_dict(), "task": self.task, "station": self.station.to_dict(),
                "radius": self.radius, "orbit_s": self.orbit_s}


def stations(runs) -> list:
    """The distinct ground stations of the policies of ``runs`` (a fleet's drones, flown
    or their specs), in the order they first appear."""
    out: dict = {}
    for r in runs:
        for p in getattr(r, "policies", ()):
            st = getattr(p, "station", None)
            if isinstance(st, GroundStation):
                out[id(st)] = st
    return list(out.values())


__all__ = ["GroundStation", "SharedSearch", "stations"]
