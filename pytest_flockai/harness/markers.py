"""The plugin's markers, parsed once at collection into frozen dataclasses.

``@pytest.mark.kpi(flight_time_s=">= 24 min", ..., flight=None)``: KPI budgets,
checked after the test body against every flight the test flew (or only the
flight named ``flight``); dotted KPIs go in a positional dict.
``@pytest.mark.flockai(drone=, pilot=, world=, tasks=, probes=, seed=, until=,
wind=, name=, max_regression=, abs_tol=)``: quick settings for the fixtures, a
per-test regression threshold (a percent, or ``{kpi: percent}``) and per-KPI
absolute tolerances (``{kpi: value in its SI unit}``, over ``kpis.abs_tolerance``).

A bad marker does not raise at collection: ``Markers.error`` holds the
message and the test errors at setup, before anything flies.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass

import pytest

from .. import budgets as _budgets
from .. import kpis as _kpis
from ..errors import ConfigError, close_matches

FLOCKAI_KEYS = ("drone", "pilot", "world", "tasks", "probes", "seed", "until", "wind", "name",
                "max_regression", "abs_tol")


@dataclass(frozen=True)
class FlightBudget:
    flight: str | None          # None: every flight of the test
    budget: _budgets.Budget


@dataclass(frozen=True)
class Markers:
    """What a test's markers say: its budgets, its regression threshold (None:
    the session's; a percent; or a tuple of (kpi, percent)), or the error."""

    budgets: tuple = ()
    max_regression: object = None
    error: str | None = None
    abs_tol: tuple = ()         # ((kpi, SI value), ...): absolute tolerances of this test

    @property
    def per_kpi_regression(self) -> dict | None:
        return dict(self.max_regression) if isinstance(self.max_regression, tuple) else None


def _error(item, marker: str, msg: str) -> Markers:
    return Markers(error=f"pytest-flockai: bad @pytest.mark.{marker} on {item.nodeid}: {msg}")


def parse(item) -> Markers:
    try:
        budgets = _kpi_budgets(item)
    except ConfigError as exc:
        return _error(item, "kpi", str(exc))
    for mark in item.iter_markers("flockai"):
        if mark.args:
            return _error(item, "flockai", f"positional arguments {mark.args!r} are not allowed; "
                                           f"use keywords: {', '.join(FLOCKAI_KEYS)}")
        for key in mark.kwargs:
            if key not in FLOCKAI_KEYS:
                return _error(item, "flockai", f"unknown setting {key!r}"
                                               f"{close_matches(key, FLOCKAI_KEYS)}; allowed: "
                                               f"{', '.join(FLOCKAI_KEYS)}")
    try:
        reg = regression_setting(closest(item, "max_regression"))
        atol = abs_tol_setting(closest(item, "abs_tol"))
    except ConfigError as exc:
        return _error(item, "flockai", str(exc))
    return Markers(budgets=budgets, max_regression=reg, abs_tol=atol)


def _kpi_budgets(item) -> tuple:
    seen: dict = {}
    for mark in item.iter_markers("kpi"):    # closest first: it wins
        kwargs = dict(mark.kwargs)
        flight = kwargs.pop("flight", None)
        if flight is not None and not isinstance(flight, str):
            raise ConfigError(f"flight = {flight!r} is not allowed; expected the name of a "
                              f"flight (a str) or None for every flight")
        specs: dict = {}
        for arg in mark.args:
            if not isinstance(arg, dict):
                raise ConfigError(f"positional argument {arg!r} is not allowed; write budgets "
                                  f"as kpi_name='<= 1.5 s' or a dict {{'probe.metric': '<= 3'}}")
            specs.update(arg)
        specs.update(kwargs)
        if not specs:
            raise ConfigError("no budget given; write e.g. "
                              "@pytest.mark.kpi(flight_time_s='>= 24 min')")
        for kpi, text in specs.items():
            seen.setdefault((flight, kpi), _budgets.parse(kpi, text))
    known = None
    for _, kpi in seen:
        if "." in kpi and _kpis.get(kpi) is None:
            known = _custom_kpis(item) if known is None else known
            _check_custom(kpi, known)
    return tuple(FlightBudget(f, b) for (f, _), b in seen.items())


def _custom_kpis(item) -> dict:
    """{probe name: {its KPI names}} known at collection: the probe classes defined
    in the test's module or a conftest.py (a probe publishes ``<name>.<metric>``)
    and the ``flockai`` marker's probe objects. Probes made elsewhere are not
    known here, and their KPIs are checked after the flight."""
    out: dict = {}

    def add(name, metrics):
        if isinstance(name, str) and name:
            out.setdefault(name, set()).update(
                f"{name}.{getattr(m, 'name', m)}" for m in metrics or ())
    base = sys.modules.get("pytest_flockai.probes.base")
    if base is None:                  # never imported: no probe exists (and none is loaded here)
        return out
    Probe = base.Probe
    module = getattr(getattr(item, "module", None), "__name__", None)
    stack = list(Probe.__subclasses__())
    while stack:
        cls = stack.pop()
        stack += cls.__subclasses__()
        home = cls.__module__
        if not getattr(cls, "builtin", False) and (home == module or
                                                    home.rsplit(".", 1)[-1] == "conftest"):
            add(cls.__dict__.get("name"), cls.__dict__.get("metrics"))
    probes = closest(item, "probes")
    for p in (probes if isinstance(probes, (list, tuple)) else [probes] if probes else []):
        if isinstance(p, Probe) and not p.builtin:
            add(p.name, p.metrics)
    return out


def _check_custom(kpi: str, known: dict) -> None:
    prefix = kpi.split(".", 1)[0]
    metrics = known.get(prefix)
    if metrics and kpi not in metrics:
        raise ConfigError(f"budget on {kpi!r}: probe {prefix!r} has no KPI {kpi!r}"
                          f"{close_matches(kpi, sorted(metrics))}; it publishes: "
                          f"{', '.join(sorted(metrics))}")


def closest(item, key):
    """The value of ``key`` in the closest ``flockai`` marker, or None."""
    for mark in item.iter_markers("flockai"):
        if key in mark.kwargs:
            return mark.kwargs[key]
    return None


def regression_setting(value):
    """``max_regression``: None, a percent for every KPI, or ``{kpi: percent}``
    (returned as a sorted tuple of pairs, so the dataclass stays frozen)."""
    def pct(field, v):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
            raise ConfigError(f"{field} = {v!r} is not allowed; expected a percentage >= 0 "
                              f"(e.g. 2.5 for 2.5 %)")
        return float(v)
    if value is None:
        return None
    if isinstance(value, dict):
        out = []
        for kpi, v in value.items():
            if _kpis.get(kpi) is None and "." not in str(kpi):
                raise ConfigError(f"max_regression: unknown KPI {kpi!r}"
                                  f"{close_matches(str(kpi), _kpis.names())}")
            out.append((kpi, pct(f"max_regression[{kpi!r}]", v)))
        return tuple(sorted(out))
    return pct("max_regression", value)


def abs_tol_setting(value) -> tuple:
    """``abs_tol``: None or ``{kpi: value >= 0 in the KPI's SI unit}`` -> sorted pairs."""
    if value is None:
        return ()
    if not isinstance(value, dict):
        raise ConfigError(f"abs_tol = {value!r} is not allowed; expected {{kpi: value >= 0 "
                          f"in the KPI's SI unit}}, e.g. {{'energy_total_j': 5}}")
    out = []
    for kpi, v in value.items():
        if _kpis.get(kpi) is None and "." not in str(kpi):
            raise ConfigError(f"abs_tol: unknown KPI {kpi!r}{close_matches(str(kpi), _kpis.names())}")
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not v >= 0 or v == math.inf:
            raise ConfigError(f"abs_tol[{kpi!r}] = {v!r} is not allowed; expected a number >= 0")
        out.append((kpi, float(v)))
    return tuple(sorted(out))


#: marker settings read by the plugin's own fixture of that name (else by ``mission``)
READ_BY = {"drone": "drone", "pilot": "pilot", "world": "world", "tasks": "tasks",
           "probes": "probes", "seed": "mission", "until": "mission", "wind": "mission",
           "name": "mission"}


def ignored_settings(item) -> list[tuple[str, str]]:
    """(setting, fixture) pairs of the ``flockai`` marker that a fixture the user
    overrode will never read: the overriding fixture wins, as pytest's closest
    fixture always does."""
    info = getattr(item, "_fixtureinfo", None)
    defs = getattr(info, "name2fixturedefs", None) or {}
    out = []
    for mark in item.iter_markers("flockai"):
        for key in mark.kwargs:
            fixture = READ_BY.get(key)
            fds = defs.get(fixture) if fixture else None
            if not fds:
                continue
            module = getattr(fds[-1].func, "__module__", "")
            if module != __name__.rsplit(".", 1)[0] + ".fixtures" and (key, fixture) not in out:
                out.append((key, fixture))
    return out


def warn_ignored(item) -> None:
    for key, fixture in ignored_settings(item):
        item.warn(pytest.PytestWarning(
            f"pytest-flockai: @pytest.mark.flockai({key}=...) on {item.nodeid} is ignored: the "
            f"`{fixture}` fixture is overridden (in a conftest.py or the test module) and an "
            f"overridden fixture wins over the marker; set {key} in your fixture, or read the "
            f"marker there with request.node.get_closest_marker('flockai')"))
