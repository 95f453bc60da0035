"""Runs the probes of one flight: schedules them on the simulated clock,
validates what they return, stores samples, feeds live subscribers.

Cheap when nothing is due: the mission compares the clock with
``hub.next_due`` (one float comparison per control tick).
"""

from __future__ import annotations

import math
import queue as _queue
from collections.abc import Iterable
from numbers import Real

import pandas as pd

from .. import kpis as _kpis
from ..errors import ConfigError, close_matches
from .base import Probe
from .builtin import BUILTIN, default_probes

MAX_ERRORS_PER_PROBE = 10


class RunView:
    """What probes can see of a flight; the mission fills it before each sample.

    Attributes: ``t`` (s), ``position``, ``velocity`` (tuples), ``stage``,
    ``phase_time`` (takeoff, hover, move, accelerating, landing seconds),
    ``distance_m``, ``max_speed_mps``, ``tracking_error_max_m``, ``crashed``,
    ``battery_usable_j``, ``battery_v_min``, ``battery_loss_j``, ``cpu_time_s``, ``io_time_s``, ``mem_utilization``,
    ``bytes_in``, ``bytes_out``, ``packets_in``, ``packets_out``,
    ``task_kpis`` (dict of the ML tasks' KPIs so far), ``sensors`` (latest
    readings by sensor name), ``drone`` and ``mission``.
    """

    def __init__(self, drone, meter, *, mission=None):
        self.mission = mission
        self.drone = drone
        self._meter = meter
        self.t = 0.0
        self.position = (0.0, 0.0, 0.0)
        self.velocity = (0.0, 0.0, 0.0)
        self.stage = "takeoff"
        self.phase_time = [0.0] * 6
        self.distance_m = self.max_speed_mps = self.tracking_error_max_m = 0.0
        self.crashed = False
        self.battery_usable_j = drone.battery.energy_j
        self.cpu_time_s = self.io_time_s = 0.0
        self.mem_utilization = 0.0
        self.bytes_in = self.bytes_out = self.packets_in = self.packets_out = 0
        self.task_kpis: dict = {}
        self.task_kpis_by_task: dict = {}
        self.sensors: dict = {}

    @property
    def battery_v_min(self) -> float:
        """Lowest terminal voltage of the battery under load so far (V)."""
        return self._meter.battery.v_min

    @property
    def battery_loss_j(self) -> float:
        """I^2 R loss inside the battery so far (J); it drains the battery, not a load."""
        return self._meter.loss_j

    def energy_by_top(self) -> dict:
        """Energy so far (J) per top-level component (motors, proc, comm...)."""
        return self._meter.totals_by_top()

    @property
    def energy_breakdown(self) -> dict:
        """Energy so far (J) per component and sub-component."""
        return self._meter.breakdown()


def resolve_probes(user: Probe | Iterable[Probe] | None) -> list[Probe]:
    """The built-in probes, with the user's probes added; a user probe named like
    a built-in one (of the same class) replaces it, e.g. to change its period
    or disable it."""
    if user is None:
        user = []
    elif isinstance(user, Probe):
        user = [user]
    try:
        user = list(user)
    except TypeError:
        raise ConfigError(f"probes = {user!r} is not a list of Probe objects") from None
    probes = default_probes()
    by_name = {p.name: i for i, p in enumerate(probes)}
    builtin_names = {cls.name: cls for cls in BUILTIN}
    seen = set()
    for p in user:
        if not isinstance(p, Probe):
            raise ConfigError(f"probes: {p!r} is not a Probe (subclass fa.probes.Probe or use FunctionProbe)")
        if p.name in seen:
            raise ConfigError(f"probes: two probes are named {p.name!r}; probe names must be unique")
        seen.add(p.name)
        if p.name in builtin_names:
            if not isinstance(p, builtin_names[p.name]):
                raise ConfigError(f"probe name {p.name!r} clashes with a built-in probe; choose another name")
            probes[by_name[p.name]] = p
            continue
        for m in p.metrics:
            if m.name in _builtin_metric_names():
                raise ConfigError(f"probe {p.name!r}: metric {m.name!r} clashes with the built-in "
                                  f"KPI {m.name!r}; choose another metric name")
        probes.append(p)
    return probes


def _builtin_metric_names():
    return {n for n, k in _kpis.REGISTRY.items() if "." not in n}


class ProbeHub:
    """Samples the enabled probes of one flight, each on its own period; a probe or
    subscriber that fails is recorded in ``errors`` and the flight goes on."""

    def __init__(self, probes: list[Probe], subscribers=()) -> None:
        self.probes = [p for p in probes if p.enabled]
        self._next = [p.period_s for p in self.probes]   # first sample one period in
        self.next_due = min(self._next) if self._next else math.inf
        self.samples: dict[str, tuple[list, list]] = {p.name: ([], []) for p in self.probes}
        self.errors: list[dict] = []
        self._err_count = {p.name: 0 for p in self.probes}
        self.subscribers = list(subscribers)
        self.final: dict[str, dict] = {}

    def bind(self, view) -> None:
        """Call every probe's ``bind(view)`` once before the flight."""
        for p in list(self.probes):
            try:
                p.bind(view)
            except Exception as exc:  # a failing probe is reported, the flight goes on
                self._fail(p, 0.0, exc)

    def sample(self, t: float, view, *, force: bool = False) -> None:
        """Collect the probes due at ``t`` (every probe when ``force``)."""
        nxt = self._next
        for i, p in enumerate(self.probes):
            if force or t >= nxt[i] - 1e-9:
                if not force:
                    while nxt[i] <= t + 1e-9:
                        nxt[i] += p.period_s
                values = self._collect(p, t, view)
                if values is None:
                    continue
                row = tuple(values.get(m, math.nan) for m in p._metric_names)
                ts, rows = self.samples[p.name]
                rows.append(row)
                ts.append(t)
                if force:
                    self.final[p.name] = values
                if self.subscribers:
                    self._publish(t, p, values)
        self.next_due = min(nxt) if nxt else math.inf

    def _collect(self, p: Probe, t, view):
        try:
            values = p.collect(view)
            if not isinstance(values, dict):
                raise ConfigError(f"probe {p.name!r}: collect() returned {type(values).__name__}, "
                                  f"expected a dict {{metric: number}}")
            for k, v in values.items():
                if k not in p._metric_names:
                    raise ConfigError(f"probe {p.name!r}: collect() returned unknown metric {k!r}"
                                      f"{close_matches(str(k), p._metric_names)}; its metrics: "
                                      f"{', '.join(p._metric_names)}")
                if (type(v) is not float and (isinstance(v, bool) or not isinstance(v, Real))) or v != v:
                    raise ConfigError(f"probe {p.name!r}: metric {k!r} = {v!r} is not a number")
            return values
        except Exception as exc:
            self._fail(p, t, exc)
            return None

    def _fail(self, p, t, exc):
        self._err_count[p.name] = self._err_count.get(p.name, 0) + 1
        if self._err_count[p.name] <= MAX_ERRORS_PER_PROBE:
            self.errors.append({"t": round(float(t), 6), "kind": "probe_error", "probe": p.name,
                                "error": f"{type(exc).__name__}: {exc}"})

    def _publish(self, t, p, values):
        msg = {"t": t, "probe": p.name, "values": {p.column(k): v for k, v in values.items()}}
        for s in list(self.subscribers):
            try:
                if isinstance(s, _queue.Queue) or hasattr(s, "put_nowait"):
                    s.put_nowait(msg)
                else:
                    s(msg)
            except Exception as exc:
                self.errors.append({"t": round(float(t), 6), "kind": "subscriber_error",
                                    "subscriber": repr(s), "error": f"{type(exc).__name__}: {exc}"})
                self.subscribers.remove(s)

    # -- results ------------------------------------------------------------
    def kpis(self) -> dict:
        """KPI name -> value from each probe's last sample."""
        out = {}
        for p in self.probes:
            vals = self.final.get(p.name)
            if vals is None:
                continue
            for m in p.metrics:
                if m.name in vals:
                    name = p.column(m.name)
                    if not p.builtin:
                        _kpis.register(name, m.unit, m.better, m.description)
                    out[name] = float(vals[m.name])
        return out

    def frames(self) -> dict[str, pd.DataFrame]:
        """One DataFrame of samples per probe, indexed by simulated time. A flight stopped by
        the wall-clock watchdog (``max_wall_s``) can be interrupted between a sample's two
        appends: the frame keeps the samples that have both a time and a row."""
        out = {}
        for p in self.probes:
            ts, rows = self.samples[p.name]
            n = min(len(ts), len(rows))
            cols = [p.column(m) for m in p._metric_names]
            out[p.name] = pd.DataFrame(rows[:n], columns=cols, index=pd.Index(ts[:n], name="t"),
                                       dtype=float)
        return out
