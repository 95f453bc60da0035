"""Policies: clocked components that decide during the flight from what the drone knows.

A ``Policy`` runs every ``period_s`` simulated seconds (after the built-in components of that tick)
and calls ``decide(t, drone)``. ``drone`` is a ``Cockpit``: the drone's own view, never the
simulator's truth:

- ``drone.results(task)``: the task results *delivered* since the last call (``Delivered``: capture
  and delivery time, detections, the pose the drone believed it had at capture), after inference
  latency, queueing and the link;
- ``drone.position`` / ``velocity`` / ``yaw`` / ``attitude``: the navigation state it flies on (the estimate with
  ``Mission(fly_on="estimate")``); ``drone.battery``: the battery monitor's remaining fraction;
  ``drone.link``: distance to the ground station and whether the tasks' radio reaches it;
  ``drone.stage``; ``drone.probe(name)``: the last sample of a probe (``energy``, ``compute``,
  ``comm``, yours; not ``flight`` or ``ml``, which are scored against the truth).

Actions (each an event ``{"kind": "policy", "policy": name, "action": ...}`` in ``result.events``,
counted in ``policy.<name>.triggers``): ``set_period``, ``set_model``, ``set_execution``,
``enable``, ``disable`` a task; ``fly(pilot)`` (replace the plan), ``goto``, ``orbit``, ``hold``,
``resume`` (back to the mission's own plan where it was left), ``return_home``, ``land``. Plan
actions need the pilot stage (or the way home, which they end); asked at another stage (take-off,
landing) they are refused (an event ``policy_refused``, the flight goes on). ``drone.mode(name)``
names what the policy is doing; ``policy.<name>.time_<mode>_s`` is the time spent in each."""

from __future__ import annotations

import math

from .. import _check
from .. import kpis as _kpis
from ..clock import Clocked
from ..control.pilots import Hover, Orbit, Pilot, Waypoints
from ..control.stages import LANDING, PILOT, RETURN, STAGES, TAKEOFF
from ..control.tracking import Goto, Resume, plan_left, yaw_of
from ..errors import ConfigError, close_matches
from ..ml.detections import parse_detections
from ..ml.models import as_model
from ..ml.task import EXECUTIONS
from . import attitude as _attitude
from . import fence as _fence
from . import reserved as _reserved
from .inputs import Delivered, Link

#: built-in probes scored against the simulator's truth: no policy reads them
TRUTH_PROBES = ("flight", "ml")


class Cockpit:
    """What a policy sees and can do (see the module docstring)."""

    def __init__(self, run, policy: Policy):
        self._run, self._policy = run, policy
        self._st = run.vehicle
        self._stages = run.stages
        self._sched = run.scheduler
        self._runners = {r.task.name: r for r in run.scheduler.runners}
        self._seen = dict.fromkeys(self._runners, 0)
        self._survey: tuple | None = None      # (the mission's plan, t left, setpoint then)
        self._refused: set = set()            # (action, stage) already refused
        cams = [s for s in run.suite.sensors if hasattr(s, "lens")] if hasattr(run.suite, "sensors") else []
        self.camera = cams[0] if cams else None
        self.t = 0.0

    # -- what the drone knows --------------------------------------------------
    @property
    def position(self) -> tuple:
        """(x, y, z) m, as the drone's estimator knows it."""
        q = self._st.qc
        return (q[0], q[1], q[2])

    @property
    def velocity(self) -> tuple:
        """(vx, vy, vz) m/s, as the drone's estimator knows it."""
        v = self._st.vc
        return (v[0], v[1], v[2])

    @property
    def yaw(self) -> float:
        """Heading (rad)."""
        return yaw_of(self._st.qc[3:7])

    @property
    def attitude(self) -> _attitude.Attitude:
        """Roll, pitch, yaw (rad) and compass heading (policy/attitude.py)."""
        return _attitude.attitude_of(self._st.qc[3:7])

    @property
    def battery(self) -> float:
        """Battery remaining, a fraction of the usable charge."""
        return self._st.battery_remaining

    @property
    def stage(self) -> str:
        """The stage the drone is in ("takeoff", "pilot", "return", "landing", "done")."""
        return STAGES[self._st.stage]

    @property
    def link(self) -> Link:
        """Distance to the ground station and the radio's range (``Link``)."""
        runners = list(self._runners.values())
        gs = runners[0].task.ground_station if runners else (0.0, 0.0, 0.0)
        rng = runners[0].link.range_m() if runners else math.inf
        return Link(math.dist(self.position, gs), rng)

    def probe(self, name: str) -> dict:
        """The last sample of probe ``name`` ({metric: value}, empty before its first);
        the built-in ``flight`` and ``ml`` probes are not readable (they are scored
        against the truth: tracking error, recall)."""
        hub = self._run.hub
        names = [p.name for p in hub.probes if p.name not in TRUTH_PROBES]
        if name not in names:
            raise ConfigError(f"policy {self._policy.name!r}: probe = {name!r} is not a probe "
                              f"the drone can read{close_matches(name, names)}; allowed: "
                              f"{', '.join(map(repr, names))}")
        ts, rows = hub.samples[name]
        if not rows:
            return {}
        p = next(p for p in hub.probes if p.name == name)
        return dict(zip(p._metric_names, rows[-1]))

    def results(self, task: str) -> list:
        """The results of ``task`` delivered since the last call, in delivery order."""
        r = self._runner(task)
        r.advance(self.t)
        evs = r.events[self._seen[task]:]
        self._seen[task] = len(r.events)
        return [self._delivered(r, e) for e in evs]

    def _delivered(self, r, e) -> Delivered:
        dets = None
        if e.ok and e.prediction is not None:
            t = r.task
            cam = self.camera
            hw = (cam.height, cam.width) if cam is not None else (240, 320)
            try:
                dets = parse_detections(e.prediction, hw, n_classes=len(t.classes),
                                        where=f"task {t.name!r}", decode=t.decode,
                                        score_threshold=t.score_threshold,
                                        iou_threshold=t.iou_threshold).above(t.score_threshold)
            except ConfigError:
                dets = None
        nav = self._sched.capture_nav.get(round(float(e.t_capture), 6))
        return Delivered(task=e.task, t_capture=e.t_capture, t_delivered=e.t_done, ok=e.ok,
                         detections=dets, count=e.count, nav=nav, prediction=e.prediction)

    def _runner(self, task):
        r = self._runners.get(task)
        if r is None:
            raise ConfigError(f"policy {self._policy.name!r}: task = {task!r} is not a task of "
                              f"the mission{close_matches(task, self._runners)}; allowed: "
                              f"{', '.join(map(repr, self._runners)) or 'none'}")
        return r

    # -- actions on tasks ------------------------------------------------------
    def set_period(self, task: str, period_s: float) -> None:
        """Run ``task`` every ``period_s`` seconds from now."""
        r = self._runner(task)
        p = _check.positive("period_s", period_s, where=f"policy {self._policy.name!r}")
        self._sched.retask(r, self.t, period_s=p)
        self._log("set_period", task=task, period_s=p)

    def set_model(self, task: str, model) -> None:
        """Run ``task`` with another model from now (anything ``Task(model=...)`` takes)."""
        r = self._runner(task)
        self._sched.retask(r, self.t, model=as_model(model))
        self._log("set_model", task=task, model=str(getattr(r.task.model, "name", "model")))

    def set_execution(self, task: str, execution: str) -> None:
        """Run ``task`` on board or remotely (``ml.task.EXECUTIONS``) from now."""
        r = self._runner(task)
        where = f"policy {self._policy.name!r}"
        ex = _check.choice("execution", execution, EXECUTIONS, where=where)
        if ex == "remote" and not getattr(r.task.model, "needs_pixels", True):
            raise ConfigError(f"{where}: set_execution({task!r}, 'remote') is not allowed: its "
                              f"model reads the truth, not pixels; there is no frame to send")
        self._sched.retask(r, self.t, execution=ex)
        self._log("set_execution", task=task, execution=ex)

    def disable(self, task: str) -> None:
        """Stop running ``task`` (no more frames taken for it)."""
        self._sched.retask(self._runner(task), self.t, enabled=False)
        self._log("disable", task=task)

    def enable(self, task: str) -> None:
        """Run ``task`` again."""
        self._sched.retask(self._runner(task), self.t, enabled=True)
        self._log("enable", task=task)

    # -- actions on the flight plan ------------------------------------------
    def fly(self, pilot: Pilot, *, action: str = "fly", **info) -> bool:
        """Replace the plan with ``pilot`` now (pilot stage only); False when refused."""
        if not isinstance(pilot, Pilot):
            raise ConfigError(f"policy {self._policy.name!r}: fly({pilot!r}) is not a Pilot")
        if self._st.stage not in (PILOT, RETURN):
            return self._refuse(action)
        if self._survey is None:
            self._survey = plan_left(self._stages.pilot, self.t, self._st.sp)
        self._stages.replace_pilot(self.t, pilot)
        self._log(action, **info)
        return True

    def goto(self, x: float, y: float, z: float | None = None, speed: float = 5.0,
             yaw: float | None = None) -> bool:
        """Fly to (x, y, z) (z: the current altitude when None) and hover there heading
        ``yaw`` (rad, as ``yaw``; None: east, 0); False when refused (not pilot stage)."""
        z, yaw = self.position[2] if z is None else z, _attitude.goto_yaw(self._policy.name, yaw)
        why = _fence.refusal(self, x, y, z)            # outside the world or a geofence
        info = {} if yaw is None else {"yaw": yaw}
        return self.fly(Goto((x, y, z), speed, yaw), action="goto", x=float(x), y=float(y),
                        z=float(z), **info) if why is None else self._refuse("goto", reason=why)

    def orbit(self, x: float, y: float, radius: float = 10.0, speed: float = 3.0,
              altitude: float | None = None) -> bool:
        """Circle (x, y) at ``radius`` m (altitude: the current one when None); False
        when refused."""
        alt = self.position[2] if altitude is None else altitude
        why = _fence.refusal(self, x, y, alt, radius)
        return self.fly(Orbit((x, y), radius, alt, speed), action="orbit", x=float(x), y=float(y),
                        radius=float(radius)) if why is None else self._refuse("orbit", reason=why)

    def hold(self) -> bool:
        """Hover where the drone is; False when refused."""
        x, y, z = self.position
        return self.fly(Hover(max(z, 0.5)), action="hold", x=float(x), y=float(y), z=float(z))

    def resume(self) -> bool:
        """Back to the mission's own plan where it was left (nothing to do if never left)."""
        if self._survey is None:
            return False
        if self._st.stage != PILOT:
            return self._refuse("resume")
        plan, t_left, sp = self._survey
        self._survey = None
        self._stages.replace_pilot(self.t, Resume(plan, t_left, sp, getattr(plan, "speed", 5.0)))
        self._log("resume")
        return True

    @property
    def plan_pilot(self):
        """The mission's plan (the pilot left for an orbit or goto, else the one flown)."""
        return self._survey[0] if self._survey is not None else self._stages.pilot

    def plan_ahead(self) -> list:
        """The mission plan's waypoints not reached yet, [(x, y, z), ...]; when the plan
        was left (orbit, goto), first the setpoint where it was left. [] outside the pilot
        stage or when the plan is not a ``Waypoints`` pilot (``ZigZag`` is one)."""
        plan, left = self.plan_pilot, None
        if self._survey is not None:
            left = self._survey[2]
        if isinstance(plan, Resume):           # on the way back to a plan left earlier
            back = plan
            plan, left = back.plan, (left if getattr(back, "_back", False) else back.at)
        if self._st.stage != PILOT or not isinstance(plan, Waypoints):
            return []
        path = getattr(plan, "path", None)
        ahead = list(plan.points[path.leg if path is not None else 0:])
        if left is not None:
            ahead.insert(0, tuple(float(v) for v in left[:3]))
        return ahead

    def replan(self, points, **info) -> bool:
        """Make ``Waypoints(points)`` the mission's plan from now on (at the plan's speed;
        a later ``resume`` comes back to it); False when refused (outside the pilot stage)."""
        if self._st.stage != PILOT:
            return self._refuse("replan")
        plan = self._survey[0] if self._survey is not None else self._stages.pilot
        self._survey = None
        self._stages.replace_pilot(self.t, Waypoints(points, getattr(plan, "speed", 5.0)))
        self._log("replan", points=len(points), **info)
        return True

    def return_home(self) -> bool:
        """Fly back to the pad and land; False when refused (already returning)."""
        if self._st.stage not in (PILOT, TAKEOFF):
            return self._refuse("return_home")
        self._stages.go_home(self.t)
        self._log("return_home")
        return True

    def land(self) -> bool:
        """Land where the drone is; False when refused (already landing)."""
        if self._st.stage >= LANDING:
            return self._refuse("land")
        self._stages.land_here(self.t)
        self._log("land")
        return True

    def mode(self, name: str) -> None:
        """Name what the policy is doing now (time in each mode is a KPI)."""
        self._policy._set_mode(self.t, str(name))

    # -- bookkeeping -----------------------------------------------------------
    def _log(self, action: str, **info) -> None:
        self._policy.triggers += 1
        self._run.event(self.t, "policy", policy=self._policy.name, action=action, **info)

    def _refuse(self, action: str, **info) -> bool:
        key = (action, self._st.stage, info.get("reason"))
        if key not in self._refused:    # once per action, stage and reason, also when alternating
            self._refused.add(key)
            self._run.event(self.t, "policy_refused", policy=self._policy.name, action=action,
                            stage=self.stage, **info)
        return False


class Policy(Clocked):
    """Base class: subclass and implement ``decide(t, drone)`` (module docstring).
    ``check(mission)`` validates against the mission before anything flies."""

    #: mode names whose time is always reported (0 when never entered)
    modes: tuple = ()

    def __init_subclass__(cls, **kw) -> None:
        super().__init_subclass__(**kw)
        _reserved.check_class(cls, RESERVED)

    def __setattr__(self, name: str, value) -> None:
        if name in RESERVED:        # self.step = 0 would make the loop call a number
            _reserved.check_attr(self, name, value, RESERVED)
        super().__setattr__(name, value)

    def __init__(self, name: str | None = None, period_s: float = 0.1) -> None:
        _check.overrides(self, Policy, "decide", "(t, drone)")
        nm = name if name is not None else type(self).__name__.lower()
        if not isinstance(nm, str) or not nm or "." in nm:
            raise ConfigError(f"{type(self).__name__}: name = {nm!r} is not allowed; expected a "
                              f"non-empty string without '.' (it names KPIs)")
        self.name = nm
        self.period_s = _check.positive("period_s", period_s, where=f"policy {nm!r}")

    def check(self, mission) -> None:
        """Raise ConfigError when the policy cannot work in ``mission`` (override)."""

    def bind(self, run) -> None:
        super().bind(run)
        self.drone = Cockpit(run, self)
        self.triggers = 0
        self._mode: str | None = None
        self._mode_t = 0.0
        self._time_in: dict = {m: 0.0 for m in self.modes}
        self.start(run)

    def start(self, run) -> None:
        """Per-flight set-up of a subclass (called from ``bind``)."""

    def step(self, t: float) -> None:
        t = round(t, 9)           # the summed physics steps' drift: 25.0, not 24.99999999999
        self.drone.t = t
        self.decide(t, self.drone)
        self.advance_clock()

    def decide(self, t: float, drone: Cockpit) -> None:  # pragma: no cover - interface
        """Look at ``drone`` (a ``Cockpit``) at simulated time ``t`` and act (override)."""
        raise NotImplementedError

    def _set_mode(self, t: float, mode: str) -> None:
        if mode == self._mode:
            return
        self._close_mode(t)
        self._mode, self._mode_t = mode, t
        self.drone._run.event(t, "policy_mode", policy=self.name, mode=mode)

    def _close_mode(self, t: float) -> None:
        if self._mode is not None:
            self._time_in[self._mode] = self._time_in.get(self._mode, 0.0) + t - self._mode_t
            self._mode_t = t

    def finish(self, t: float) -> None:
        self._close_mode(t)

    def kpis(self, run) -> dict:
        """``policy.<name>.triggers`` and ``policy.<name>.time_<mode>_s`` (registered)."""
        out = {f"policy.{self.name}.triggers": float(self.triggers)}
        for m, s in self._time_in.items():
            out[f"policy.{self.name}.time_{m}_s"] = s
        register_kpis(self.name, self._time_in)
        return out

    def to_dict(self) -> dict:
        return {"type": type(self).__name__, "name": self.name, "period_s": self.period_s}


#: the methods the flight loop calls on a policy: never data (policy/reserved.py)
RESERVED = _reserved.reserved(Policy)


def register_kpis(name: str, modes=()) -> None:
    """Register a policy's KPI names (so budgets and reports know their units)."""
    _kpis.register(f"policy.{name}.triggers", "count", None, f"policy {name!r}: actions taken")
    for m in modes:
        _kpis.register(f"policy.{name}.time_{m}_s", "s", None,
                       f"policy {name!r}: time spent in mode {m!r}")


__all__ = ["Cockpit", "Delivered", "Link", "Policy", "RESERVED", "TRUTH_PROBES", "register_kpis"]
