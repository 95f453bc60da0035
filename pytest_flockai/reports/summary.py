"""What the Markdown summary and the HTML dashboard show, from a JSON report.

Both read the ``pytest-flockai/1`` document (``report.build_report``) only, so
they render the same for a run with or without pytest-xdist, and for a report
merged from CI shards (``flockai merge``).
"""

from __future__ import annotations

import math

from .. import kpis as _kpis
from .. import report as _report

HEADLINE = ("flight_time_s", "endurance_s", "energy_total_j", "mean_power_w", "battery_remaining",
            "inference_latency_p50_s", "recall", "map50", "crashed")


def broken_budgets(doc: dict) -> list[dict]:
    return [{"test": t["nodeid"], **b} for t in doc.get("tests", ())
            for b in t.get("budgets", ()) if b.get("verdict") != "pass"]


def budgets(doc: dict) -> list[dict]:
    return [{"test": t["nodeid"], **b} for t in doc.get("tests", ()) for b in t.get("budgets", ())]


def regressions(doc: dict) -> list[dict]:
    return [{"test": t["nodeid"], **r} for t in doc.get("tests", ())
            for r in t.get("regressions", ())]


def flights(doc: dict) -> list[dict]:
    """One row per (test, flight): test, flight, outcome, cache status, KPIs."""
    return [{"test": t["nodeid"], "flight": f["name"], "outcome": t["outcome"],
             "cache": (f.get("cache") or {}).get("status"), "kpis": f.get("kpis") or {},
             "end_reason": f.get("end_reason")}
            for t in doc.get("tests", ()) for f in t.get("flights", ())]


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


def counts(doc: dict) -> str:
    s = doc.get("summary", {})
    parts = [f"{s.get(k)} {k}" for k in ("passed", "failed", "error", "skipped", "xfailed",
                                         "xpassed") if s.get(k)]
    return f"{s.get('tests', 0)} test(s) ({', '.join(parts) or 'none run'}), " \
           f"{s.get('flights', 0)} flight(s)"
