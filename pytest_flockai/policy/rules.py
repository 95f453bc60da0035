"""Rules: ``when`` a condition on what the drone knows holds, do actions.

``Rule("battery < 0.4", then=[SetPeriod("det", 2.0)], otherwise=[SetPeriod("det", 0.5)])``
checks its condition every ``period_s``; when it turns true it takes the ``then``
actions, when it turns false again the ``otherwise`` actions (``once=True``: the
``then`` actions at most once). Modes ``"idle"`` / ``"active"`` give
``policy.<name>.time_active_s``.

Signals a condition may name (``"<signal> <op> <number>"``, op one of < <= > >= ==):
``battery`` (remaining fraction), ``time_s``, ``altitude_m``, ``home_distance_m``,
``link_distance_m``, and per task ``<task>.count`` (the last delivered count),
``<task>.detections`` (boxes in the last delivered result), ``<task>.latency_s``
(capture to delivery of the last result), and ``<probe>.<metric>``, a probe's last
sample (``energy.mean_power_w``, ``compute.cpu_utilization``, your probes'; not the
``flight`` and ``ml`` probes, scored against the truth). A name that is none of
these is a ConfigError when the Mission is built.
"""

from __future__ import annotations

import math
import operator
import re

from .. import _check
from ..control.pilots import _extent
from ..errors import ConfigError, close_matches
from ..ml.task import EXECUTIONS
from .base import TRUTH_PROBES, Policy

SIGNALS = ("battery", "time_s", "altitude_m", "home_distance_m", "link_distance_m")
TASK_SIGNALS = ("count", "detections", "latency_s")
_OPS = {"<": operator.lt, "<=": operator.le, ">": operator.gt, ">=": operator.ge, "==": operator.eq}
_COND = re.compile(r"^\s*([A-Za-z_][\w.\-]*)\s*(<=|>=|==|<|>)\s*([-+]?\d*\.?\d+(?:[eE][-+]?\d+)?)\s*$")


class Action:
    """One thing a rule does: ``apply(drone)``; ``tasks`` it names (checked)."""

    tasks: tuple = ()

    def check(self, mission, where: str) -> None:
        names = [t.name for t in mission.tasks]
        for task in self.tasks:
            if task not in names:
                raise ConfigError(f"{where}: {self!r} names task = {task!r}, which is not a task "
                                  f"of the mission{close_matches(task, names)}; allowed: "
                                  f"{', '.join(map(repr, names)) or 'none (the mission has no tasks)'}")

    def apply(self, drone) -> None:  # pragma: no cover - interface
        raise NotImplementedError

    def __repr__(self):
        args = ", ".join(repr(v) for v in vars(self).values())
        return f"{type(self).__name__}({args})"


class _TaskAction(Action):
    def __init__(self, task: str):
        if not isinstance(task, str) or not task:
            raise ConfigError(f"{type(self).__name__}: task = {task!r} is not a task name")
        self.task = task

    @property
    def tasks(self):
        return (self.task,)


class SetPeriod(_TaskAction):
    """Run ``task`` every ``period_s`` from now."""

    def __init__(self, task: str, period_s: float):
        super().__init__(task)
        self.period_s = _check.positive("period_s", period_s, where="SetPeriod")

    def apply(self, drone):
        drone.set_period(self.task, self.period_s)


class SetModel(_TaskAction):
    """Run ``task`` with ``model`` from now."""

    def __init__(self, task: str, model):
        super().__init__(task)
        self.model = model

    def apply(self, drone):
        drone.set_model(self.task, self.model)


class SetExecution(_TaskAction):
    """Run ``task`` ``"onboard"`` or ``"remote"`` from now."""

    def __init__(self, task: str, execution: str):
        super().__init__(task)
        self.execution = _check.choice("execution", execution, EXECUTIONS, where="SetExecution")

    def check(self, mission, where):
        super().check(mission, where)
        tk = next(t for t in mission.tasks if t.name == self.task)
        if self.execution == "remote" and not getattr(tk.model, "needs_pixels", True):
            raise ConfigError(f"{where}: SetExecution({self.task!r}, 'remote') is an action the "
                              f"drone cannot take: the task's model reads the truth, not pixels, "
                              f"so there is no frame to send")

    def apply(self, drone):
        drone.set_execution(self.task, self.execution)


class EnableTask(_TaskAction):
    def apply(self, drone):
        drone.enable(self.task)


class DisableTask(_TaskAction):
    def apply(self, drone):
        drone.disable(self.task)


class GoTo(Action):
    """Fly to (x, y, z) and hold there (z None: the current altitude)."""

    def __init__(self, x: float, y: float, z: float | None = None, speed: float = 5.0):
        self.x = _extent("x", _check.number("x", x, where="GoTo"), "GoTo")
        self.y = _extent("y", _check.number("y", y, where="GoTo"), "GoTo")
        self.z = None if z is None else _extent("z", _check.positive("z", z, where="GoTo"), "GoTo")
        self.speed = _check.positive("speed", speed, where="GoTo")

    def apply(self, drone):
        drone.goto(self.x, self.y, self.z, self.speed)


class Hold(Action):
    def apply(self, drone):
        drone.hold()


class ResumePlan(Action):
    def apply(self, drone):
        drone.resume()


class ReturnHome(Action):
    def apply(self, drone):
        drone.return_home()


class Land(Action):
    def apply(self, drone):
        drone.land()


def parse_condition(text: str, where: str):
    """(signal, op name, threshold) of ``"battery < 0.4"``."""
    m = _COND.match(text) if isinstance(text, str) else None
    if m is None:
        raise ConfigError(f"{where}: when = {text!r} is not a condition; expected "
                          f"'<signal> <op> <number>', e.g. 'battery < 0.4' (op: < <= > >= ==)")
    return m.group(1), m.group(2), float(m.group(3))


class Rule(Policy):
    """``when`` -> ``then`` actions, ``otherwise`` when it stops holding (module docstring)."""

    modes = ("idle", "active")

    def __init__(self, when: str, then=(), *, otherwise=(), once: bool = False,
                 name: str = "rule", period_s: float = 1.0):
        super().__init__(name, period_s)
        where = f"Rule {self.name!r}"
        self.when = when
        self.signal, self.op, self.threshold = parse_condition(when, where)
        self.then, self.otherwise = self._actions(then, "then"), self._actions(otherwise, "otherwise")
        if not isinstance(once, bool):
            raise ConfigError(f"{where}: once = {once!r} is not allowed; expected True or False")
        self.once = once

    def _actions(self, acts, field):
        try:
            acts = tuple(acts if isinstance(acts, (list, tuple)) else (acts,))
        except TypeError:
            acts = ()
        for i, a in enumerate(acts):
            if not isinstance(a, Action):
                raise ConfigError(f"Rule {self.name!r}: {field}[{i}] = {a!r} is not an action; "
                                  f"use fa.policy.SetPeriod, SetModel, SetExecution, EnableTask, "
                                  f"DisableTask, GoTo, Hold, ResumePlan, ReturnHome or Land")
        return acts

    def check(self, mission) -> None:
        where = f"Rule {self.name!r}"
        names = [t.name for t in mission.tasks]
        allowed = list(SIGNALS) + [f"{n}.{s}" for n in names for s in TASK_SIGNALS]
        allowed += [f"{p.name}.{m}" for p in mission.probes if p.name not in TRUTH_PROBES
                    for m in p._metric_names]
        if self.signal not in allowed:
            raise ConfigError(f"{where}: when = {self.when!r} names signal {self.signal!r}, which "
                              f"the drone does not know{close_matches(self.signal, allowed)}; "
                              f"allowed: {', '.join(allowed)}")
        for a in self.then + self.otherwise:
            a.check(mission, where)

    def start(self, run) -> None:
        self._on = False
        self._fired = False
        self._last: dict = {}

    def _value(self, t, drone) -> float:
        s = self.signal
        if s == "battery":
            return drone.battery
        if s == "time_s":
            return t
        if s == "altitude_m":
            return drone.position[2]
        if s == "home_distance_m":
            return math.dist(drone.position[:2], drone._st.home[:2])
        if s == "link_distance_m":
            return drone.link.distance_m
        task, _, what = s.rpartition(".")
        if task not in drone._runners:                    # a probe's metric
            return drone.probe(task).get(what, math.nan)
        for r in drone.results(task):
            self._last[task] = r
        r = self._last.get(task)
        if r is None:
            return math.nan
        if what == "count":
            return math.nan if r.count is None else float(r.count)
        if what == "detections":
            return 0.0 if r.detections is None else float(len(r.detections))
        return r.t_delivered - r.t_capture

    def decide(self, t, drone) -> None:
        if self._mode is None:
            drone.mode("idle")
        on = _OPS[self.op](self._value(t, drone), self.threshold)
        if on and not self._on and not (self.once and self._fired):
            self._fired = True
            drone.mode("active")
            for a in self.then:
                a.apply(drone)
        elif not on and self._on:
            drone.mode("idle")
            for a in self.otherwise:
                a.apply(drone)
        self._on = on

    def to_dict(self):
        return {**super().to_dict(), "when": self.when, "then": [repr(a) for a in self.then],
                "otherwise": [repr(a) for a in self.otherwise], "once": self.once}


__all__ = ["Action", "DisableTask", "EnableTask", "GoTo", "Hold", "Land", "ResumePlan",
           "ReturnHome", "Rule", "SIGNALS", "SetExecution", "SetModel", "SetPeriod",
           "parse_condition"]
