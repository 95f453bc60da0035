"""pytest-html (when installed and ``--html`` is given): each test's KPI and budget
table, its regressions against the baseline and its pictures (flight path,
energy breakdown, attached pictures) as extras of the test's row."""

from __future__ import annotations

import html as _html

from ..reports import files as _report


def active(config) -> bool:
    return config.pluginmanager.has_plugin("html") and bool(
        getattr(config.option, "htmlpath", None))


def _table(cls: str, headers, rows) -> str:
    """An HTML table of already-escaped cells."""
    head = "".join(f"<th>{h}</th>" for h in headers)
    body = "".join("<tr>" + "".join(f"<td>{c}</td>" for c in row) + "</tr>" for row in rows)
    return f'<table class="{cls}"><tr>{head}</tr>{body}</table>'


def table(payload: dict) -> str:
    """The KPI table of each flight, then the budgets and regressions, as HTML."""
    e = _html.escape
    parts = []
    for f in payload.get("flights", ()):
        src = " (from the flight cache)" if (f.get("cache") or {}).get("status") == "hit" else ""
        parts.append(f"<p><b>flight {e(f['name'])}</b>: {e(str(f.get('end_reason')))}{src}</p>")
        parts.append(_table("flockai-kpis", ("KPI", "value"),
                            ((e(k), e(_report.format_kpi(k, v)))
                             for k, v in (f.get("kpis") or {}).items())))
    budgets = payload.get("budgets") or []
    if budgets:
        parts.append(_table("flockai-budgets",
                            ("flight", "KPI", "budget", "actual", "margin", "verdict"),
                            ((e(str(b.get("flight"))), e(b["kpi"]), e(str(b.get("budget"))),
                              e(str(b.get("actual_text"))), e(str(b.get("margin_text"))),
                              e(str(b.get("verdict")))) for b in budgets)))
    regs = payload.get("regressions") or []
    if regs:
        parts.append(_table("flockai-regressions",
                            ("flight", "KPI", "baseline", "actual", "change"),
                            ((e(r["flight"]), e(r["kpi"]),
                              e(_report.format_kpi(r["kpi"], r["baseline"])),
                              e(_report.format_kpi(r["kpi"], r["actual"])),
                              f"{r['change_pct']:+.2f}%") for r in regs)))
    return "<div>" + "".join(parts) + "</div>"


def add(report, payload: dict, pictures: list[dict]) -> None:
    """Append the extras to ``report.extras`` (pytest-html 4)."""
    try:
        from pytest_html import extras
    except ImportError:
        return
    new = [extras.html(table(payload))]
    new += [extras.png(p["data"], p["title"]) for p in pictures]
    report.extras = list(getattr(report, "extras", None) or []) + new
