"""One test's verdict: its budgets against its flights, its KPIs against the
baseline, and the failure message (None when everything holds)."""

from __future__ import annotations

import warnings

import pytest

from .. import budgets as _budgets
from .. import kpis as _kpis
from ..errors import ConfigError, close_matches
from ..reports import compare as _compare
from ..reports import files as _report
from ..reports import scenario as _scenario
from . import sweeps as _sweeps


def check(item, st, session, body_failed: bool = False) -> str | None:
    """Evaluate budgets and the baseline into ``st``; return the failure message or None.

    ``body_failed``: the test body raised (its error is the test's verdict; a
    timeout is not reported as "flew no mission")."""
    st.verdicts, st.regressions, st.problems = [], [], []
    st.baseline_missing, st.baseline_unmatched = [], []
    sweep_message = None
    if st.sweep is not None:
        sweep_message = _sweeps.check(item, st)
    elif st.markers.budgets and (st.flights or not body_failed):
        _budget_verdicts(item, st)
    st.compact_examples(failed=body_failed or any(not v.passed for v in st.verdicts))
    if session.baseline is not None and st.flights:
        _baseline(item, st, session)
    parts = list(st.problems)
    broken = [v for v in st.verdicts if not v.passed]
    if sweep_message:
        parts.append(sweep_message)
    elif broken:
        parts.append(f"pytest-flockai: {len(broken)} of {len(st.verdicts)} KPI budget(s) broken "
                     f"in {item.nodeid}:\n" + _budgets.table(st.verdicts))
    if st.regressions:
        parts.append(regression_text(item, st, session))
    if st.baseline_missing and session.missing_baseline == "fail":
        parts.append(missing_text(item.nodeid, st, session))
    return "\n".join(parts) or None


def regression_text(item, st, session) -> str:
    """The gate's message: the scenario change against the baseline first, then one row
    per KPI family (a task's ``det.*`` twin and the flight's KPI folded), biggest first."""
    deltas = [_compare.Delta(item.nodeid, r["flight"], r["kpi"], r["baseline"], r["actual"],
                             r["better"], "regression") for r in st.regressions]
    groups = _compare.group(deltas, {})
    rows = [[g.worst.flight if len(g.flights) == 1 else f"{len(g.flights)} flights",
             g.family + (f" (x{g.count})" if g.count > 1 else ""),
             _report.format_kpi(g.worst.kpi, g.worst.base),
             _report.format_kpi(g.worst.kpi, g.worst.new), _compare.format_change(g.worst),
             g.worst.better or ""] for g in groups]
    changes = _scenario_changes(item, st, session)
    cause = "".join(f"\n  scenario change: {c}" for c in changes)
    return (f"pytest-flockai: {len(groups)} KPI regression(s) against baseline "
            f"{session.baseline_path} (max {limit_text(session, st)}) in {item.nodeid}:{cause}\n"
            + _report.table(["flight", "KPI family", "baseline", "actual", "change", "better"],
                            rows))


def _scenario_changes(item, st, session) -> list[str]:
    if not hasattr(session, "baseline_scenarios"):
        session.baseline_scenarios = _compare.load_scenarios(session.baseline_path)
    base = session.baseline_scenarios.get(item.nodeid) or {}
    new = {f.name: _scenario.summary(f.result.scenario) for f in st.flights}
    return _scenario.changes_of({item.nodeid: base}, {item.nodeid: new}, item.nodeid)


def warn(item, st, session) -> None:
    """Artifacts that could not be written: a warning, once per session."""
    if st.warnings and not getattr(session, "warned_artifacts", False):
        session.warned_artifacts = True
        warnings.warn(pytest.PytestWarning(st.warnings[0]), stacklevel=2)


def _baseline(item, st, session) -> None:
    base = session.baseline.get(item.nodeid) or {}
    flown = [f.name for f in st.flights]
    st.baseline_missing = [n for n in flown if n not in base]
    st.baseline_unmatched = [n for n in base if n not in flown]
    if not base:
        return
    limit = session.max_regression
    reg = st.markers.max_regression
    if reg is not None and not isinstance(reg, tuple):
        limit = reg
    abs_tol = {**getattr(session, "abs_tol", {}), **dict(st.markers.abs_tol)}
    st.regressions = _report.regressions({f.name: f.kpis for f in st.flights}, base,
                                         limit, per_kpi=st.markers.per_kpi_regression,
                                         abs_tol=abs_tol)


def missing_text(nodeid, st, session) -> str:
    """"not in baseline" for one test: the flights the baseline has no entry for."""
    if not st.baseline_unmatched:
        return (f"pytest-flockai: {nodeid} is not in baseline {session.baseline_path} "
                f"(flights {', '.join(st.baseline_missing)}): its KPIs were not compared")
    hints = "".join(f"; {n!r}{close_matches(n, st.baseline_unmatched)}"
                    for n in st.baseline_missing)
    return (f"pytest-flockai: {nodeid}: flight(s) {', '.join(st.baseline_missing)} not in "
            f"baseline {session.baseline_path}, which has {', '.join(st.baseline_unmatched)} "
            f"for this test (a renamed or mistyped flight?{hints}): not compared")


def _budget_verdicts(item, st) -> None:
    fb = st.markers.budgets
    if not st.flights:
        st.problems.append(
            f"pytest-flockai: {item.nodeid} has @pytest.mark.kpi budgets "
            f"({', '.join(sorted({x.budget.kpi for x in fb}))}) but flew no mission; use "
            f"the `flight` fixture or call Mission.run() in the test")
        return
    names = [f.name for f in st.flights]
    for x in fb:
        fname, b = x.flight, x.budget
        targets = st.flights if fname is None else [f for f in st.flights if f.name == fname]
        if not targets:
            st.problems.append(f"pytest-flockai: @pytest.mark.kpi(flight={fname!r}) on "
                               f"{item.nodeid}: no flight named {fname!r}"
                               f"{close_matches(fname, names)}; this test flew: "
                               f"{', '.join(names)}")
            continue
        if "." in b.kpi and _kpis.get(b.kpi) is not None:
            try:   # a custom KPI registered since collection: check its unit now
                b = _budgets.parse(b.kpi, b.text)
            except ConfigError as exc:
                st.problems.append(f"pytest-flockai: {exc}")
                continue
        for f in targets:
            if b.kpi not in f.kpis:
                st.problems.append(
                    f"pytest-flockai: budget {b.kpi} {b.text!r}: flight {f.name!r} did "
                    f"not produce KPI {b.kpi!r}{close_matches(b.kpi, f.kpis)}; it "
                    f"produced: {', '.join(f.kpis)}")
                continue
            st.verdicts.append(b.verdict(f.kpis[b.kpi], flight=f.name))


def limit_text(session, st) -> str:
    m = st.markers.max_regression
    if isinstance(m, tuple):
        extra = ", ".join(f"{k} {v:g}%" for k, v in m)
        return f"{session.max_regression:g}%, {extra}"
    return f"{(session.max_regression if m is None else m):g}%"
