"""What the Markdown summary and the HTML dashboard show, from a JSON report.

Both read the ``pytest-flockai/1`` document (``report.build_report``) only, so
they render the same for a run with or without pytest-xdist, and for a report
merged from CI shards (``flockai merge``).
"""

from __future__ import annotations

import math

from .. import kpis as _kpis
from . import compare as _compare
from . import files as _report
from . import scenario as _scenario

HEADLINE = ("flight_time_s", "endurance_s", "energy_total_j", "mean_power_w", "battery_remaining",
            "inference_latency_p50_s", "recall", "map50", "crashed")


#: pytest's outcomes that make a run fail
FAILING = ("failed", "error", "crashed", "interrupted")


def ok(doc: dict) -> bool:
    """The run passed, as pytest said: its exit status is 0 (a report without one:
    no test failed). Broken budgets of an xfail test do not make it red."""
    status = doc.get("exitstatus")
    if status is not None:
        return int(status) == 0
    s = doc.get("summary", {})
    return not any(s.get(k) for k in FAILING)


def budget_state(outcome: str, b: dict) -> str:
    """What a budget row means for the run: "pass", "broken" (its test failed),
    "xfail" (broken in a test expected to fail) or "caught" (broken inside a
    ``budgets.check`` the test expected to raise: the test passed)."""
    if b.get("verdict") == "pass":
        return "pass"
    if outcome in ("xfailed", "xpassed"):
        return "xfail"
    if outcome in ("passed", "skipped"):
        return "caught"
    return "broken"


def budgets(doc: dict) -> list[dict]:
    """Every budget row, with its test, its test's outcome and its ``state``."""
    return [{"test": t["nodeid"], "outcome": t.get("outcome"), **b,
             "state": budget_state(t.get("outcome", ""), b)}
            for t in doc.get("tests", ()) for b in t.get("budgets", ())]


def broken_budgets(doc: dict) -> list[dict]:
    """The budgets broken in a failed test: those that fail the run."""
    return [b for b in budgets(doc) if b["state"] == "broken"]


def per_test(rows: list[dict]) -> list[dict]:
    """Budget rows counted once per test: a budget broken by several flights of a test
    (or by every hypothesis example, or by the marker and a check) is one."""
    seen: dict = {}
    for b in rows:
        seen.setdefault((b["test"], b.get("kpi"), b.get("budget")), b)
    return list(seen.values())


def expected_broken(doc: dict) -> list[dict]:
    """Budgets broken where pytest expected it (xfail tests, ``pytest.raises`` around check)."""
    return [b for b in budgets(doc) if b["state"] in ("xfail", "caught")]


def regressions(doc: dict) -> list[dict]:
    return [{"test": t["nodeid"], **r} for t in doc.get("tests", ())
            for r in t.get("regressions", ())]


def regression_groups(doc: dict, base_scenarios: dict | None = None) -> tuple[list, dict]:
    """The run's regressions against the baseline as ``compare.Group`` rows (one per
    KPI family and test, biggest first, grouped by cause), and ``{cause: [tests]}``
    from the scenario changes against the baseline's scenarios (when it kept them)."""
    new_scen = _scenario.of_report(doc)
    causes: dict = {}
    by_test: dict = {}
    for t in doc.get("tests", ()):
        lines = _scenario.changes_of(base_scenarios or {}, new_scen, t["nodeid"])
        if lines:
            by_test[t["nodeid"]] = lines
            causes.setdefault("; ".join(lines), []).append(t["nodeid"])
    deltas = [_compare.Delta(r["test"], r["flight"], r["kpi"], r.get("baseline"), r.get("actual"),
                             r.get("better"), "regression") for r in regressions(doc)]
    return _compare.group(deltas, by_test), causes


def flights(doc: dict) -> list[dict]:
    """One row per (test, flight): test, flight, outcome, cache status, KPIs."""
    return [{"test": t["nodeid"], "flight": f["name"], "outcome": t["outcome"],
             "cache": (f.get("cache") or {}).get("status"), "kpis": f.get("kpis") or {},
             "cache_key": (f.get("cache") or {}).get("key"),
             "end_reason": f.get("end_reason"), "wall_time_s": f.get("wall_time_s")}
            for t in doc.get("tests", ()) for f in t.get("flights", ())]


def distinct_flights(rows: list[dict], key=lambda r: r.get("cache_key")) -> list[dict]:
    """The flights of ``rows`` counted once each: a session fixture's flight is listed by
    every test that uses it, under one cache key (``key(row)``; rows without one are all
    distinct). The terminal's cache line, the headline and the dashboard count with this
    one rule."""
    unique: dict[object, dict] = {}
    for i, r in enumerate(rows):
        k = key(r)
        unique.setdefault(k if k else ("row", i), r)
    return list(unique.values())


def cache_hits(doc: dict) -> int:
    """How many distinct flights of the run came from the flight cache."""
    return sum(r["cache"] == "hit" for r in distinct_flights(flights(doc)))


def kpi_columns(doc: dict, limit: int | None = None) -> list[str]:
    """The headline KPIs present in the run, then every budgeted KPI, then the rest."""
    present: dict = {}
    for row in flights(doc):
        for k in row["kpis"]:
            present.setdefault(k, None)
    cols = [k for k in HEADLINE if k in present]
    for b in budgets(doc):
        if b["kpi"] in present and b["kpi"] not in cols:
            cols.append(b["kpi"])
    if limit is None:
        cols += [k for k in present if k not in cols]
    return cols[:limit] if limit else cols


def better(kpi: str) -> str:
    info = _kpis.get(kpi)
    return (info.better or "") if info is not None else ""


def fmt(kpi: str, v) -> str:
    return _report.format_kpi(kpi, v)


def fmt_pct(v) -> str:
    if v is None:
        return "n/a"
    v = float(v)
    return f"{v:+.2f}%" if math.isfinite(v) else ("+inf%" if v > 0 else "-inf%")


OUTCOMES = ("passed", "failed", "error", "skipped", "xfailed", "xpassed", "crashed",
            "interrupted")


def counts(doc: dict) -> str:
    """pytest's counts: ``26 test(s) (24 passed, 2 xfailed), 30 flight(s)`` (a flight that
    several tests list, a shared fixture's, counted once)."""
    s = doc.get("summary", {})
    parts = [f"{s.get(k)} {k}" for k in OUTCOMES if s.get(k)]
    n = len(distinct_flights(flights(doc))) if doc.get("tests") else s.get("flights", 0)
    return f"{s.get('tests', 0)} test(s) ({', '.join(parts) or 'none run'}), {n} flight(s)"


def _expected_why(expected: list[dict]) -> str:
    """``"1 xfail, 2 caught by pytest.raises"``: where the expected broken budgets were."""
    n_xfail = sum(b["state"] == "xfail" for b in expected)
    parts = [f"{n_xfail} xfail" if n_xfail else "",
             f"{len(expected) - n_xfail} caught by pytest.raises" if len(expected) > n_xfail else ""]
    return ", ".join(p for p in parts if p)


def headline(doc: dict) -> str:
    """The one line of a run: pytest's counts, then the budgets and regressions."""
    broken, expected = per_test(broken_budgets(doc)), per_test(expected_broken(doc))
    regs, _ = regression_groups(doc)
    cached = cache_hits(doc)
    why = _expected_why(expected)
    extra = [f"{len(broken)} budget(s) broken" if broken else "every budget holds"
             if not expected else f"{len(expected)} budget(s) broken where expected ({why})"]
    if broken and expected:
        extra.append(f"{len(expected)} more where expected ({why})")
    if regs:
        extra.append(f"{len(regs)} regression(s) (KPI families)")
    if cached:
        extra.append(f"{cached} flight(s) from the cache")
    return f"{'passed' if ok(doc) else 'FAILED'}: {counts(doc)}; {'; '.join(extra)}"


def slowest(doc: dict, n: int = 3) -> list[dict]:
    """The ``n`` flights that took the most wall time to fly (cache hits cost nothing)."""
    rows = [r for r in flights(doc) if r["cache"] != "hit" and r.get("wall_time_s")]
    return sorted(rows, key=lambda r: -r["wall_time_s"])[:n]


def decisions(test: dict) -> list[str]:
    """One line per flight of ``test`` with policy events: what its policies did, when."""
    out = []
    for f in test.get("flights") or ():
        evs = f.get("policy_events") or []
        if evs:
            words = [f"{e.get('t', 0):.1f} s {e.get('action') or e.get('mode') or e['kind']}"
                     + (f" ({e['reason']})" if e.get("reason") else "") for e in evs[:30]]
            more = len(evs) - 30 + f.get("policy_events_dropped", 0)
            out.append(f"{f['name']}: " + ", ".join(words) + (f", and {more} more" if more > 0 else ""))
    return out
