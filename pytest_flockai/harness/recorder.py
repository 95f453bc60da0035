"""The flights of one test, kept in ``item.stash``, and the one naming rule.

Every ``Mission.run()`` while a test runs reaches ``TestState.record`` through
the recording sink the plugin opens for the test (``pytest_flockai.recording``):
the ``flight`` fixture, your own fixtures and calls in the test body, also a
flight that ended in a ``SimulationError``. A FlightResult the test receives
from a fixture it did not fly itself (a module- or session-scoped fixture
flown during an earlier test) is adopted when the test body starts.

Names, the same on every path: ``Mission(name=...)``, else the name of the
fixture that returned the flight, else ``"flight"``; repeats get ``-2``,
``-3``... So a test's flight names never depend on which tests ran before it.
"""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import pytest

from ..errors import ConfigError
from ..reports import files as _report
from .markers import Markers

if TYPE_CHECKING:      # the core loads on first use
    from ..result import FlightResult

STATE = pytest.StashKey["TestState"]()


@dataclass
class Flight:
    """One flight of a test: its result and where its name comes from."""

    result: FlightResult
    explicit: str | None = None    # Mission(name=...)
    fixture: str | None = None     # the fixture that returned it
    name: str = "flight"           # final, unique within the test
    example: int = 0               # the hypothesis example that flew it (0: none)

    @property
    def kpis(self) -> dict:
        """The flight's KPIs."""
        return self.result.kpis


@dataclass
class TestState:
    """What the plugin knows about one test."""

    item: pytest.Item
    markers: Markers = field(default_factory=Markers)
    flights: list = field(default_factory=list)       # [Flight], in the order flown
    verdicts: list = field(default_factory=list)      # [budgets.Verdict]
    regressions: list = field(default_factory=list)
    problems: list = field(default_factory=list)      # kpi marker misuse found after the body
    finished: bool = False                              # names, hooks and artifacts done
    baseline_missing: list = field(default_factory=list)    # flights the baseline lacks
    baseline_unmatched: list = field(default_factory=list)  # baseline flights not flown
    example: int = 0                                    # hypothesis examples run so far
    hypothesis: dict | None = None                      # their compact summary
    warnings: list = field(default_factory=list)       # e.g. artifacts that could not be written
    sweep: object = None                                # the DataFrame of @pytest.mark.flockai_sweep
    sweep_files: list = field(default_factory=list)     # its envelope CSV and picture
    checks: dict = field(default_factory=dict)          # budgets.check() in the body, by budget

    __test__ = False  # not a pytest test class

    def reset(self) -> None:
        """A new attempt of the test (pytest-rerunfailures): nothing of the
        earlier attempts counts, names start again at ``flight``."""
        self.flights, self.verdicts, self.regressions, self.problems = [], [], [], []
        self.baseline_missing, self.baseline_unmatched, self.warnings = [], [], []
        self.finished, self.example, self.hypothesis = False, 0, None
        self.sweep, self.sweep_files, self.checks = None, [], {}

    def record(self, mission: object, result: FlightResult) -> None:
        """A flight of this test, flown now (its name is settled when it is added)."""
        explicit = getattr(mission, "name", None) or (result.scenario or {}).get("name")
        self._add(Flight(result, explicit=explicit, example=self.example))

    def record_check(self, result, verdicts) -> None:
        """Budgets the test body checked itself (``budgets.check``/``evaluate``): per
        (flight, KPI, budget) the worst verdict is kept (a broken one, else the
        smallest margin), with how often it was checked (hypothesis examples)."""
        names = {id(f.result): f.name for f in self.flights}
        flight = names.get(id(result))
        for v in verdicts:
            key = (flight, v.kpi, v.budget)
            old = self.checks.get(key)
            n = 1 if old is None else old[1] + 1
            if old is None or (old[0].passed and not v.passed) or (
                    old[0].passed == v.passed and v.margin < old[0].margin):
                self.checks[key] = (v, n)
            else:
                self.checks[key] = (old[0], n)

    def next_example(self) -> None:
        """A hypothesis example starts (the plugin wraps the test's inner function)."""
        self.example += 1

    def compact_examples(self, failed: bool) -> None:
        """A hypothesis test keeps the flights of its last example in full when it
        failed (hypothesis runs the shrunk failing example last) and none when it
        passed; the rest is a count and the range of each KPI."""
        if self.example < 2 and not any(f.example > 1 for f in self.flights):
            return
        ranges: dict = {}
        for f in self.flights:
            for k, v in f.kpis.items():
                try:
                    v = float(v)
                except (TypeError, ValueError):
                    continue
                if math.isfinite(v):
                    lo, hi = ranges.get(k, (v, v))
                    ranges[k] = (min(lo, v), max(hi, v))
        last = max((f.example for f in self.flights), default=0)
        kept = [f for f in self.flights if failed and f.example == last]
        self.hypothesis = {"examples": self.example, "flights": len(self.flights),
                           "kept": len(kept), "kpi_ranges": {k: list(v) for k, v in ranges.items()}}
        worst: dict = {}
        for v in self.verdicts:           # per budget: a failing one, else the smallest margin
            key = (v.kpi, v.budget)
            w = worst.get(key)
            if w is None or (w.passed and not v.passed) or (
                    w.passed == v.passed and v.margin < w.margin):
                worst[key] = v
        self.verdicts = list(worst.values())
        before = {f.name: f for f in kept}
        self.flights = kept
        self._name()                     # kept flights: "<name>-example-<n>", never "flight"
        renamed = {old: f.name for old, f in before.items()}
        self.checks = {(renamed.get(k[0], k[0]), *k[1:]): v for k, v in self.checks.items()}

    def _add(self, flight: Flight) -> None:
        """A flight of this test; the derived-KPI hooks run on it now, so the test
        body sees their KPIs."""
        item = self.item
        for extra in item.config.hook.pytest_flockai_derived_kpis(result=flight.result, item=item):
            _add_derived(flight.result, extra)
        self.flights.append(flight)
        self._name()

    def adopt_fixture_flights(self) -> None:
        """Name the flights fixtures returned after their fixture, and adopt those
        flown before this test (module- or session-scoped fixtures)."""
        mine = {id(f.result): f for f in self.flights}
        for argname, value in (getattr(self.item, "funcargs", None) or {}).items():
            if not _is_flight_result(value):
                continue
            f = mine.get(id(value))
            if f is None:
                f = Flight(value, explicit=(value.scenario or {}).get("name"))
                self._add(f)
                mine[id(value)] = f
            f.fixture = f.fixture or argname
        self._name()

    def _name(self) -> None:
        taken: set = set()
        for f in self.flights:
            base = str(f.explicit or f.fixture or "flight")
            if self.hypothesis is not None and f.example:    # a kept hypothesis example's
                base = f"{base}-example-{f.example}"
            name, k = base, 1
            while name in taken:
                k += 1
                name = f"{base}-{k}"
            f.name = name
            taken.add(name)

    def finish(self, artifacts) -> None:
        """After the body, when every flight has its final name: the artifacts.
        One that cannot be written (a full disk) is a warning, not a failure."""
        if self.finished or artifacts is None:
            return
        self.finished = True
        for f in self.flights:
            try:
                _report.write_artifacts(artifacts, self.item.nodeid, f.name, f.result)
            except OSError as exc:
                self.warnings.append(f"pytest-flockai: artifacts of {self.item.nodeid} flight "
                                     f"{f.name!r} not written to {artifacts}: "
                                     f"{exc.strerror or exc}")
                return

    def payload(self) -> dict:
        """Plain JSON data for the test report (travels through pytest-xdist)."""
        flights = [{"name": f.name, "end_reason": getattr(f.result, "end_reason", None),
                    "sim_time_s": f.result.scenario.get("sim_time_s"),
                    "wall_time_s": getattr(f.result, "wall_time_s", None),
                    "scenario": f.result.scenario, "kpis": f.result.kpis,
                    "cache": getattr(f.result, "cache", None),
                    **_decisions(f.result)} for f in self.flights]
        error = self.markers.error or ("\n".join(self.problems) or None)
        checks = [{**v.to_dict(), "flight": v.flight or k[0], "source": "check", "checked": n}
                  for k, (v, n) in self.checks.items()]
        out: dict[str, Any] = {"flights": flights, "budgets": [v.to_dict() for v in self.verdicts] + checks,
               "regressions": self.regressions, "error": error}
        if self.baseline_missing or self.baseline_unmatched:
            out["baseline_missing"] = self.baseline_missing
            out["baseline_unmatched"] = self.baseline_unmatched
        if self.hypothesis is not None:
            out["hypothesis"] = self.hypothesis
        if self.sweep is not None:
            from ..sweeps import (
                envelope_files as envelope,  # lazy: a sweep flew, so it is loaded already
            )
            out["sweep"] = envelope.summary(self.sweep, self.sweep_files)
        return _report.jsonable(out)


def _add_derived(result, extra) -> None:
    if not extra:
        return
    if not isinstance(extra, dict):
        raise ConfigError(f"pytest_flockai_derived_kpis returned {extra!r}; expected a "
                          f"dict {{kpi name: number}} or None")
    for key, value in extra.items():
        if not isinstance(key, str) or isinstance(value, bool) or not isinstance(
                value, (int, float)) and not hasattr(value, "__float__"):
            raise ConfigError(f"pytest_flockai_derived_kpis: {key!r} = {value!r} is not "
                              f"allowed; expected a str name and a number")
        result.kpis[key] = float(value)


def _is_flight_result(value) -> bool:
    """``value`` is a FlightResult, found without importing ``result`` (pandas): while
    the module was never imported, no value can be one."""
    mod = sys.modules.get("pytest_flockai.result")
    return mod is not None and isinstance(value, mod.FlightResult)


#: the events of a flight's policies that go in the reports (without
#: them, a run without --flockai-artifacts would show them nowhere): actions, modes, refusals, rejected tracks
DECISION_KINDS = ("policy", "policy_mode", "policy_refused", "track_rejected",
                  "geofence_breach")
#: at most this many per flight in the report (the artifacts keep every event)
MAX_DECISIONS = 200


def _decisions(result) -> dict:
    """``{"policy_events": [...]}`` for a flight with policy events, else {}."""
    evs = [e for e in (getattr(result, "events", None) or ()) if e.get("kind") in DECISION_KINDS]
    if not evs:
        return {}
    out: dict = {"policy_events": evs[:MAX_DECISIONS]}
    if len(evs) > MAX_DECISIONS:
        out["policy_events_dropped"] = len(evs) - MAX_DECISIONS
    return out
