"""Perception-driven policies: follow a target from a detector's boxes, search then orbit.

``Follow(task)`` flies the mission's own plan (mode ``search``) until the
tracker (``control.tracking.Tracker``) is confirmed by ``confirm`` detections of
the ``target`` class, then flies above the track (``follow``). A detection
becomes a ground point through the camera model and the pose the drone believed
it had when the frame was captured; results arrive when delivered (latency and
link included), are fused at their capture time and predicted to now. With no
result delivered for ``lost_after_s`` the track is lost (``lost``): ``on_lost`` says
what the drone does: ``"search"`` (resume the plan where it was left and look
again), ``"hold"``, ``"return_home"`` or ``"land"``.

``SearchThenOrbit(task)``: the plan (a lawnmower) until a confirmed detection,
then orbit it at ``radius`` for ``orbit_s``; with ``find`` > 1 it resumes the
search to look for the next target (a new target is one farther than ``gate_m``
from every target found). Once ``find`` targets are found: ``after="return_home"``
(go home and land) or ``"orbit"`` (keep orbiting the last one).

Old and implausible results. A result's age (delivery minus capture: inference,
queueing, the link) is known: one up to ``max_age_s`` old (Follow: ``lost_after_s``; the
searches: 3 s) is fused at its capture time and predicted to now at constant velocity, and
the lost timer counts from its delivery; an older one cannot hold a track and is rejected
(an event ``track_rejected`` with ``reason="stale"``, the KPI ``track_rejected_stale``). A
track whose estimated speed exceeds what its class can move at (``MAX_SPEED_MPS``: a false
positive stuck in the image moves with the drone) is dropped (``reason="implausible"``,
``track_rejected_implausible``; judged from the third hit, so it matters for Follow: the
searches act on a track at its confirmation, and judge it there with ``policy.plausible``: a
target faster than its class or moving with the drone is rejected, an event
``target_rejected`` and the KPI ``targets_rejected_implausible``).

Closed-loop KPIs (``policy/scoring.py``, from the truth after the flight, never
in a decision): ``time_to_detect_s``, ``track_error_p95_m``, ``track_lost_count``,
``track_lost_s``, ``targets_found``, ``time_to_find_all_s``.
"""

from __future__ import annotations

import math

from .. import _check
from ..control.stages import PILOT
from ..control.tracking import Track, Tracker, ground_point, yaw_of
from ..errors import ConfigError
from ..world.objects import CAR_HEIGHT, PERSON_HEIGHT
from ..world.truth import CLASSES
from . import plausible, scoring
from .base import Policy

ON_LOST = ("search", "hold", "return_home", "land")
#: what SearchThenOrbit does once it found ``find`` targets and orbited the last
AFTER = ("return_home", "orbit")
#: m/s: the fastest a target of each class is taken to move; a track estimated faster is a false
#: positive. person: the men's 100 m world record, 100 m in 9.58 s (Berlin, 2009), 10.4 m/s on
#: average over the race; vehicle: 250 km/h, the top speed German carmakers limit their cars
#: to by voluntary agreement
MAX_SPEED_MPS = {"person": 100.0 / 9.58, "vehicle": 250.0 / 3.6}
#: hits before a track's speed is judged (its velocity needs a few measurements)
SPEED_HITS = 3
#: s: the age of a result the searches (SearchThenOrbit, SharedSearch) still use
SEARCH_MAX_AGE_S = 3.0
#: m: the height of an object's centre, where a box's centre ray meets it
CENTRE_Z = {"person": PERSON_HEIGHT / 2, "vehicle": CAR_HEIGHT / 2}


def _task_of(mission, task, where):
    names = [t.name for t in mission.tasks]
    for t in mission.tasks:
        if t.name == task:
            if t.sensor != "camera":
                raise ConfigError(f"{where}: task {task!r} reads sensor {t.sensor!r}; following "
                                  f"needs boxes in a camera's frames (sensor 'camera')")
            return t
    raise ConfigError(f"{where}: task = {task!r} is not a task of the mission; allowed: "
                      f"{', '.join(map(repr, names)) or 'none (the mission has no tasks)'}")


class _Perceiving(Policy):
    """Shared by the perception policies: results to ground points, a tracker."""

    #: the searches judge a target before acting on it (``policy.plausible``)
    judges = False

    def __init__(self, task, target, name, period_s, gate_m, confirm, score):
        super().__init__(name, period_s)
        where = f"policy {self.name!r}"
        if not isinstance(task, str) or not task:
            raise ConfigError(f"{where}: task = {task!r} is not a task name")
        self.task = task
        self.target = _check.choice("target", target, CLASSES, where=where)
        self.gate_m = _check.positive("gate_m", gate_m, where=where)
        if isinstance(confirm, bool) or not isinstance(confirm, int) or confirm < 1:
            raise ConfigError(f"{where}: confirm = {confirm!r} is not allowed; expected an int >= 1")
        self.confirm = confirm
        if score is not None and not isinstance(score, str):
            raise ConfigError(f"{where}: score = {score!r} is not allowed; expected an actor's name")
        self.score = score
        self.max_age_s = SEARCH_MAX_AGE_S

    def check(self, mission) -> None:
        where = f"policy {self.name!r}"
        tk = _task_of(mission, self.task, where)
        if self.target not in tk.classes:
            raise ConfigError(f"{where}: target = {self.target!r} is not a class of task "
                              f"{self.task!r}; allowed: {', '.join(map(repr, tk.classes))}")
        reports = getattr(tk.model, "classes", None)      # an oracle says what it reports
        if reports is not None and self.target not in reports:
            raise ConfigError(f"{where}: target = {self.target!r} is not a class the model of "
                              f"task {self.task!r} reports; allowed: {', '.join(map(repr, reports))}")
        names = [a.name for a in getattr(mission, "actors", ()) if a.name]
        if self.score is not None and self.score not in names:
            raise ConfigError(f"{where}: score = {self.score!r} is not an actor of the mission; "
                              f"allowed: {', '.join(map(repr, names)) or 'none (no named actors)'}")

    def start(self, run) -> None:
        self.tracker = Tracker(gate_m=self.gate_m, confirm=self.confirm)
        cam = self.drone.camera
        self._lens = (cam.width, cam.height, cam.fov_deg, cam.pitch_deg) if cam else None
        tk = next(r.task for r in run.scheduler.runners if r.task.name == self.task)
        self._cls = tk.classes.index(self.target)
        self._z = CENTRE_Z.get(self.target, 0.0)
        self.log = scoring.Log(run)       # for the KPIs only: never read by decide()
        self.rejected = {"stale": 0, "implausible": 0}
        self._last_reject: str | None = None
        self._max_speed = MAX_SPEED_MPS.get(self.target, math.inf)
        self._navs: dict = {}             # capture time -> (x, y, yaw) believed then
        self._hits: list = []             # the track's raw hits: (t, (x, y), nav)
        self._phantoms: list = []         # offsets in the drone's frame of rejected targets
        self.targets_rejected = 0

    def measurements(self, drone) -> list:
        """[(t_capture, [(x, y), ...], t_delivered)] of the newly delivered results, in
        capture order."""
        out, self._navs = [], {}
        for r in drone.results(self.task):
            if not r.ok or r.detections is None or r.nav is None or self._lens is None:
                continue
            d = r.detections
            pts = []
            for (x0, y0, x1, y1), c in zip(d.boxes, d.cls):
                if int(c) == self._cls:
                    p = ground_point(0.5 * (x0 + x1), 0.5 * (y0 + y1), r.nav, self._lens, self._z)
                    if p is not None:
                        pts.append(p)
            self._navs[r.t_capture] = (r.nav[0], r.nav[1], yaw_of(r.nav[3:7]))
            out.append((r.t_capture, pts, r.t_delivered))
        out.sort(key=lambda m: m[0])
        return out

    def fuse(self, t_cap, pts, drone, t_del=None) -> None:
        """Update the tracker with the point nearest its prediction (or, with no track
        yet, nearest the drone); a result older than ``max_age_s`` or a track faster than
        its class can move is rejected (module docstring)."""
        if not pts:
            return
        age = 0.0 if t_del is None else float(t_del) - float(t_cap)
        if age > self.max_age_s:
            self._reject(drone, "stale", age_s=round(age, 3), max_age_s=self.max_age_s,
                         why=f"a result delivered {age:.2f} s after capture is older than "
                             f"max_age_s = {self.max_age_s:g} s: it cannot hold a track; use "
                             f"a faster link or task, or a longer lost_after_s")
            return
        nav = self._navs.get(t_cap)
        if self.judges and drone.stage not in ("pilot", "return"):
            return              # a search acts on its plan or the way home (not judged climbing)
        if self.judges and nav is not None and self._phantoms:
            pts = [p for p in pts if not plausible.masked(p, nav, self._phantoms)]
            if not pts:
                return
        tr = self.tracker
        ref = tr.predict(t_cap)[:2] if tr.x is not None else drone.position[:2]
        best = min(pts, key=lambda p: math.dist(p, ref))
        hit = tr.update(t_cap, best[0], best[1], t_delivered=t_del)
        if hit and nav is not None:
            self._hits = (self._hits if tr.hits > 1 else []) + [(t_cap, best, nav)]
        if hit and tr.hits >= SPEED_HITS \
                and tr.x is not None and math.hypot(tr.x[2], tr.x[3]) > self._max_speed:
            v = math.hypot(tr.x[2], tr.x[3])
            self._reject(drone, "implausible", speed_mps=round(v, 2),
                         max_speed_mps=round(self._max_speed, 2),
                         why=f"the track moves at {v:.1f} m/s, faster than a {self.target} "
                             f"can ({self._max_speed:.1f} m/s): a false positive")
            tr.reset()

    def plausible(self, drone) -> bool:
        """The searches, at a confirmation: is the target plausible (``policy.plausible``)?
        If not: an event ``target_rejected``, the tracker reset, the phantom remembered."""
        hits = self._hits if len(self._hits) == self.tracker.hits else []
        verdict = plausible.judge(hits, self._max_speed)
        if verdict is None or verdict[0] == "wait":
            return verdict is None
        reason, info = verdict
        self.targets_rejected += 1
        _, p, nav = hits[-1]
        if reason == "with_drone":
            self._phantoms = [*self._phantoms, plausible.offset(p, nav)][-plausible.PHANTOMS:]
        why = (f"the target moved {info['target_moved_m']:.1f} m as the drone moved "
               f"{info['drone_moved_m']:.1f} m the same way: a box fixed in the image, not a "
               f"{self.target}") if reason == "with_drone" else (
               f"the target moved at {info['speed_mps']:.1f} m/s, faster than a {self.target} "
               f"can ({info['max_speed_mps']:.1f} m/s)")
        drone._run.event(drone.t, "target_rejected", policy=self.name, reason=reason,
                         x=round(p[0], 2), y=round(p[1], 2), why=why, **info)
        self.tracker.reset()
        self._hits = []
        return False

    def _reject(self, drone, reason: str, **info) -> None:
        """Count a rejection; an event for the first of each reason in a row."""
        self.rejected[reason] += 1
        if self._last_reject != reason:
            self._last_reject = reason
            drone._run.event(drone.t, "track_rejected", policy=self.name, reason=reason, **info)

    def step(self, t: float) -> None:
        super().step(t)
        self.log.sample(t)

    def kpis(self, run) -> dict:
        out = super().kpis(run)
        out.update(self.log.kpis(self, run))
        out["track_rejected_stale"] = float(self.rejected["stale"])
        out["track_rejected_implausible"] = float(self.rejected["implausible"])
        if self.judges:
            out["targets_rejected_implausible"] = float(self.targets_rejected)
        return out


class Follow(_Perceiving):
    """Follow a target from a detection task's boxes (module docstring)."""

    modes = ("search", "follow", "lost")

    def __init__(self, task: str, *, target: str = "person", altitude: float | None = None,
                 speed: float = 12.0, confirm: int = 2, lost_after_s: float = 3.0,
                 on_lost: str = "search", gate_m: float = 15.0, name: str = "follow",
                 period_s: float = 0.1, score: str | None = None):
        super().__init__(task, target, name, period_s, gate_m, confirm, score)
        where = f"policy {self.name!r}"
        self.altitude = None if altitude is None else _check.positive("altitude", altitude, where=where)
        self.speed = _check.positive("speed", speed, where=where)
        self.lost_after_s = _check.positive("lost_after_s", lost_after_s, where=where)
        self.max_age_s = self.lost_after_s
        self.on_lost = _check.choice("on_lost", on_lost, ON_LOST, where=where)

    def start(self, run) -> None:
        super().start(run)
        self.lost_count = 0

    def decide(self, t, drone) -> None:
        for t_cap, pts, t_del in self.measurements(drone):
            self.fuse(t_cap, pts, drone, t_del)
        tr, mode = self.tracker, self._mode
        if mode is None:
            drone.mode("search")
        if mode in (None, "search", "lost"):
            if tr.x is not None and not tr.confirmed and t - tr.last_delivered > self.lost_after_s:
                tr.reset()                         # a start that was never confirmed
            if tr.confirmed and drone._st.stage == PILOT:
                alt = self.altitude if self.altitude is not None else drone.position[2]
                if drone.fly(Track(tr, alt, self.speed), action="follow"):
                    self.log.found(t, tr.predict(t)[:2])
                    drone.mode("follow")
        elif mode == "follow" and t - tr.last_delivered > self.lost_after_s:
            self.lost_count += 1
            drone._log("track_lost", since_s=round(t - tr.last_delivered, 3),
                       fallback=self.on_lost)
            drone.mode("lost")
            tr.reset()
            {"search": drone.resume, "hold": drone.hold, "return_home": drone.return_home,
             "land": drone.land}[self.on_lost]()

    def to_dict(self):
        return {**super().to_dict(), "task": self.task, "target": self.target,
                "altitude": self.altitude, "speed": self.speed, "confirm": self.confirm,
                "lost_after_s": self.lost_after_s, "on_lost": self.on_lost}


class SearchThenOrbit(_Perceiving):
    """Fly the plan until a confirmed detection, then orbit it (module docstring)."""

    judges = True

    modes = ("search", "orbit", "done")

    def __init__(self, task: str, *, target: str = "person", radius: float = 10.0,
                 speed: float = 3.0, find: int = 1, orbit_s: float = 20.0, confirm: int = 2,
                 gate_m: float = 10.0, after: str = "return_home", name: str = "search",
                 period_s: float = 0.2):
        super().__init__(task, target, name, period_s, gate_m, confirm, None)
        where = f"policy {self.name!r}"
        self.radius = _check.positive("radius", radius, where=where)
        self.speed = _check.positive("speed", speed, where=where)
        if isinstance(find, bool) or not isinstance(find, int) or find < 1:
            raise ConfigError(f"{where}: find = {find!r} is not allowed; expected an int >= 1")
        self.find = find
        self.orbit_s = _check.positive("orbit_s", orbit_s, where=where)
        self.after = _check.choice("after", after, AFTER, where=where)

    def start(self, run) -> None:
        super().start(run)
        self.found: list = []              # (x, y) of the targets found
        self._orbit_t = 0.0

    def decide(self, t, drone) -> None:
        for t_cap, pts, t_del in self.measurements(drone):
            new = [p for p in pts if all(math.dist(p, f) > self.gate_m for f in self.found)]
            self.fuse(t_cap, new, drone, t_del)
        tr = self.tracker
        if self._mode is None:
            drone.mode("search")
        if self._mode == "search":
            if tr.x is not None and not tr.confirmed and t - tr.last_delivered > self.max_age_s:
                tr.reset()
            if tr.confirmed and len(self.found) < self.find and self.plausible(drone):
                x, y = tr.predict(t)[:2]
                if drone.orbit(x, y, self.radius, self.speed):
                    self.found.append((x, y))
                    self.log.found(t, (x, y))
                    self._orbit_t = t
                    drone.mode("orbit")
                tr.reset()
        elif self._mode == "orbit" and t - self._orbit_t >= self.orbit_s:
            if len(self.found) < self.find:
                if drone.resume():
                    drone.mode("search")
            elif self.after != "orbit" and drone.return_home():
                drone.mode("done")

    def to_dict(self):
        return {**super().to_dict(), "task": self.task, "target": self.target,
                "radius": self.radius, "find": self.find, "orbit_s": self.orbit_s,
                "after": self.after}


__all__ = ["AFTER", "Follow", "MAX_SPEED_MPS", "ON_LOST", "SearchThenOrbit"]
