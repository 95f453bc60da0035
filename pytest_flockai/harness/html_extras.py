"""pytest-html (when installed and ``--html`` is given): each test's KPI and budget
table, its regressions against the baseline and its pictures (flight path,
energy breakdown, attached pictures) as extras of the test's row."""

from __future__ import annotations

import html as _html

from .. import report as _report


def active(config) -> bool:
    return config.pluginmanager.has_plugin("html") and bool(
        getattr(config.option, "htmlpath", None))


def table(payload: dict) -> str:
    """The KPI table of each flight, then the budgets and regressions, as HTML."""
    e = _html.escape
    parts = []
    for f in payload.get("flights", ()):
        rows = "".join(f"<tr><td>{e(k)}</td><td>{e(_report.format_kpi(k, v))}</td></tr>"
                       for k, v in (f.get("kpis") or {}).items())
        src = " (from the flight cache)" if (f.get("cache") or {}).get("status") == "hit" else ""
        parts.append(f"<p><b>flight {e(f['name'])}</b>: {e(str(f.get('end_reason')))}{src}</p>"
                     f'<table class="flockai-kpis"><tr><th>KPI</th><th>value</th></tr>{rows}'
                     f"</table>")
    budgets = payload.get("budgets") or []
    if budgets:
        rows = "".join(
            f"<tr><td>{e(str(b.get('flight')))}</td><td>{e(b['kpi'])}</td>"
            f"<td>{e(str(b.get('budget')))}</td><td>{e(str(b.get('actual_text')))}</td>"
            f"<td>{e(str(b.get('margin_text')))}</td><td>{e(str(b.get('verdict')))}</td></tr>"
            for b in budgets)
        parts.append('<table class="flockai-budgets"><tr><th>flight</th><th>KPI</th>'
                     f"<th>budget</th><th>actual</th><th>margin</th><th>verdict</th></tr>{rows}"
                     "</table>")
    regs = payload.get("regressions") or []
    if regs:
        rows = "".join(
            f"<tr><td>{e(r['flight'])}</td><td>{e(r['kpi'])}</td>"
            f"<td>{e(_report.format_kpi(r['kpi'], r['baseline']))}</td>"
            f"<td>{e(_report.format_kpi(r['kpi'], r['actual']))}</td>"
            f"<td>{r['change_pct']:+.2f}%</td></tr>" for r in regs)
        parts.append('<table class="flockai-regressions"><tr><th>flight</th><th>KPI</th>'
                     f"<th>baseline</th><th>actual</th><th>change</th></tr>{rows}</table>")
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
