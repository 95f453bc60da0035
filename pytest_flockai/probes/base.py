"""The probe interface (paper section 4.5, Table 1; after PyCatascopia).

A probe groups metrics that are read together. It has a ``name``, a
``period_s`` on the simulated clock, metric definitions and ``collect(view)``
returning the current values as a dict ``{metric: number}``. ``view`` is a
read-only snapshot of the flight (see ``RunView``). Probes are enabled or
disabled independently; a probe that raises is reported with its name and the
flight and the other probes go on.

A custom probe::

    class Detections(fa.probes.Probe):
        name = "app"
        metrics = (fa.probes.Metric("detections_per_min", "1/min", "ML detections per minute",
                                    better="higher", kind="gauge"),)
        def collect(self, view):
            n = view.task_kpis.get("inference_count", 0.0)
            return {"detections_per_min": 60.0 * n / max(view.t, 1e-9)}

Its values land in the telemetry as ``app.detections_per_min`` and as the KPI
``app.detections_per_min``, so a ``kpi`` budget can be set on it.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

from .. import _check
from ..errors import ConfigError

KINDS = ("gauge", "counter", "timer", "ratio")


@dataclass(frozen=True)
class Metric:
    """One quantity a probe measures: a snake_case ``name``, its ``unit``, which way
    is ``better`` ("higher", "lower" or None) and its ``kind`` (gauge, counter,
    timer or ratio)."""

    name: str
    unit: str = "1"
    description: str = ""
    better: str | None = None      # "higher", "lower" or None
    kind: str = "gauge"            # gauge, counter (never decreases), timer (seconds), ratio [0, 1]

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name.isidentifier():
            raise ConfigError(f"Metric name = {self.name!r} is not allowed; expected a "
                              f"snake_case identifier")
        _check.choice("kind", self.kind, KINDS, where=f"metric {self.name!r}")
        _check.choice("better", self.better, ("higher", "lower", None), where=f"metric {self.name!r}")


class Probe:
    """Base class of all probes. Subclasses set ``name`` and ``metrics`` and
    implement ``collect(view) -> dict``."""

    name: str = ""
    metrics: tuple[Metric, ...] = ()
    period_s: float = 1.0
    builtin: bool = False          # built-in probes publish un-prefixed KPI names

    def __init__(self, *, period_s: float | None = None, enabled: bool = True,
                 name: str | None = None) -> None:
        if name is not None:
            self.name = name
        if not isinstance(self.name, str) or not self.name or "." in self.name:
            raise ConfigError(f"probe name = {self.name!r} is not allowed; expected a non-empty "
                              f"string without '.'")
        if period_s is not None:
            self.period_s = period_s
        self.period_s = _check.positive("period_s", self.period_s, where=f"probe {self.name!r}")
        if not isinstance(enabled, bool):
            raise ConfigError(f"probe {self.name!r}: enabled = {enabled!r} is not allowed; expected True or False")
        self.enabled = enabled
        seen = set()
        for m in self.metrics:
            if not isinstance(m, Metric):
                raise ConfigError(f"probe {self.name!r}: metrics must be Metric objects, got {m!r}")
            if m.name in seen:
                raise ConfigError(f"probe {self.name!r}: metric {m.name!r} is defined twice")
            seen.add(m.name)
        self._metric_names = tuple(m.name for m in self.metrics)

    def bind(self, view) -> None:
        """Called once before the flight (optional)."""

    def collect(self, view) -> dict:  # pragma: no cover - interface
        """One sample: metric name -> value, read from ``view`` (a ``RunView``)."""
        raise NotImplementedError(f"probe {self.name!r} must implement collect(view) -> dict")

    def column(self, metric: str) -> str:
        """Telemetry column and KPI name of one of this probe's metrics."""
        return metric if self.builtin else f"{self.name}.{metric}"

    def to_dict(self) -> dict:
        """JSON-ready description for the flight's scenario."""
        return {"name": self.name, "type": type(self).__name__, "period_s": self.period_s,
                "enabled": self.enabled, "metrics": list(self._metric_names)}

    def __repr__(self):
        return f"{type(self).__name__}(name={self.name!r}, period_s={self.period_s}, enabled={self.enabled})"


class FunctionProbe(Probe):
    """A probe from a function: ``FunctionProbe("app", fn, metrics=[Metric(...)])``."""

    def __init__(self, name: str, fn: Callable[[Any], dict], metrics: Iterable[Metric], *,
                 period_s: float = 1.0, enabled: bool = True) -> None:
        if not callable(fn):
            raise ConfigError(f"probe {name!r}: fn = {fn!r} is not callable")
        self.metrics = tuple(metrics)
        self._fn = fn
        super().__init__(period_s=period_s, enabled=enabled, name=name)

    def collect(self, view) -> dict:
        """``fn(view)``: metric name -> value."""
        return self._fn(view)
