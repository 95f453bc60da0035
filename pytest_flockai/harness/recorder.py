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
from dataclasses import dataclass, field

import pytest

from .. import report as _report
from ..errors import ConfigError
from ..result import FlightResult
from .markers import Markers

STATE = pytest.StashKey["TestState"]()


@dataclass
class Flight:
    result: object                 # FlightResult
    explicit: str | None = None    # Mission(name=...)
    fixture: str | None = None     # the fixture that returned it
    name: str = "flight"           # final, unique within the test

    @property
    def kpis(self) -> dict:
        return self.result.kpis


@dataclass
class TestState:
    """What the plugin knows about one test."""

    item: object
    markers: Markers = field(default_factory=Markers)
    flights: list = field(default_factory=list)       # [Flight], in the order flown
    verdicts: list = field(default_factory=list)      # [budgets.Verdict]
    regressions: list = field(default_factory=list)
    problems: list = field(default_factory=list)      # kpi marker misuse found after the body
    finished: bool = False                              # names, hooks and artifacts done
    _props: list = field(default_factory=list)        # user_properties we added

    __test__ = False  # not a pytest test class

    def record(self, mission, result) -> None:
        explicit = getattr(mission, "name", None) or (result.scenario or {}).get("name")
        self._add(Flight(result, explicit=explicit))

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
            if not isinstance(value, FlightResult):
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
            name, k = base, 1
            while name in taken:
                k += 1
                name = f"{base}-{k}"
            f.name = name
            taken.add(name)

    def finish(self, artifacts) -> None:
        """After the body, when every flight has its final name: the artifacts."""
        if self.finished or artifacts is None:
            return
        self.finished = True
        for f in self.flights:
            _report.write_artifacts(artifacts, self.item.nodeid, f.name, f.result)

    def payload(self) -> dict:
        """Plain JSON data for the test report (travels through pytest-xdist)."""
        flights = [{"name": f.name, "end_reason": getattr(f.result, "end_reason", None),
                    "sim_time_s": f.result.scenario.get("sim_time_s"),
                    "scenario": f.result.scenario, "kpis": f.result.kpis,
                    "cache": getattr(f.result, "cache", None)} for f in self.flights]
        error = self.markers.error or ("\n".join(self.problems) or None)
        return _report.jsonable({"flights": flights,
                                 "budgets": [v.to_dict() for v in self.verdicts],
                                 "regressions": self.regressions, "error": error})

    def sync_properties(self) -> None:
        """``flockai.<kpi>`` (or ``flockai.<flight>.<kpi>``) user properties for JUnit."""
        props = []
        prefix_flight = len(self.flights) > 1
        for f in self.flights:
            for k, v in f.kpis.items():
                props.append((f"flockai.{f.name}.{k}" if prefix_flight else f"flockai.{k}",
                              _prop_value(v)))
        if props == self._props:
            return
        old = {id(p) for p in self._props}
        item = self.item
        item.user_properties[:] = [p for p in item.user_properties if id(p) not in old] + props
        self._props = props


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


def _prop_value(v) -> str:
    try:
        v = float(v)
    except (TypeError, ValueError):
        return str(v)
    return repr(v) if math.isfinite(v) else str(v)
