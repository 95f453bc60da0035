"""How results show in a notebook (``_repr_html_``): a compact summary with the
headline KPIs, the budgets last checked against the result (``budgets.check`` /
``evaluate`` keep them on it) and the flight path as a small inline SVG (no
matplotlib, nothing fetched).

``flight_html`` (a FlightResult), ``fleet_html`` (a FleetResult: one colour per
drone) and ``sweep_html`` (the DataFrame of ``fa.sweep``).
"""

from __future__ import annotations

import html
import math

from . import kpis as _kpis

HEADLINE = ("flight_time_s", "endurance_s", "energy_total_j", "mean_power_w",
            "battery_remaining", "inference_latency_p50_s", "recall", "map50", "crashed",
            "fleet.makespan_s", "fleet.coverage_fraction", "fleet.min_separation_m",
            "fleet.crashes", "fleet.energy_total_j")
#: one colour per drone (matplotlib's tab10)
COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2",
           "#7f7f7f", "#bcbd22", "#17becf")
_STYLE = ("font:13px system-ui,sans-serif;border-collapse:collapse;margin:2px 0")


def fmt(name: str, value) -> str:
    """A KPI value with its unit (fractions in percent)."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        return html.escape(str(value))
    if not math.isfinite(v):
        return str(v)
    info = _kpis.get(name)
    unit = info.unit if info is not None else ""
    if unit == "fraction" or name.startswith("energy_share_"):
        return f"{100 * v:.3g}%"
    if unit == "s" and abs(v) >= 120:
        return f"{v / 60:.4g} min"
    return f"{v:.4g} {'' if unit in ('1', 'count') else unit}".rstrip()


def _table(rows, head=None) -> str:
    e = html.escape
    th = "".join(f"<th style='text-align:left;padding:1px 6px'>{e(h)}</th>" for h in head or ())
    body = "".join("<tr>" + "".join(f"<td style='padding:1px 6px'>{c}</td>" for c in r) + "</tr>"
                   for r in rows)
    return f"<table style='{_STYLE}'>{f'<tr>{th}</tr>' if th else ''}{body}</table>"


def kpi_table(kpis: dict) -> str:
    names = [k for k in HEADLINE if k in kpis]
    rest = len(kpis) - len(names)
    rows = [[html.escape(k), fmt(k, kpis[k])] for k in names]
    return _table(rows) + (f"<small>{rest} more KPI(s) in .kpis</small>" if rest else "")


def budget_table(verdicts) -> str:
    if not verdicts:
        return ""
    rows = [["<b style='color:#176e2f'>pass</b>" if v.passed else
             "<b style='color:#b3261e'>BROKEN</b>", html.escape(v.kpi), html.escape(v.budget),
             html.escape(v.actual_text), html.escape(v.margin_text)] for v in verdicts]
    return _table(rows, ["verdict", "KPI", "budget", "actual", "margin"])


def path_svg(paths: dict, size: int = 220, min_span: float = 4.0) -> str:
    """``{label: (xs, ys)}`` seen from above as an inline SVG, equal scale, at least
    ``min_span`` metres wide, one colour per path, home as a triangle."""
    pts = [(x, y) for xs, ys in paths.values() for x, y in zip(xs, ys)
           if math.isfinite(x) and math.isfinite(y)] + [(0.0, 0.0)]
    x0, x1 = min(p[0] for p in pts), max(p[0] for p in pts)
    y0, y1 = min(p[1] for p in pts), max(p[1] for p in pts)
    span = max(x1 - x0, y1 - y0, min_span) * 1.1
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2

    def to(x, y):
        return (size * (0.5 + (x - cx) / span), size * (0.5 - (y - cy) / span))
    parts = []
    for i, (label, (xs, ys)) in enumerate(paths.items()):
        step = max(1, len(xs) // 400)
        line = " ".join(f"{a:.1f},{b:.1f}" for a, b in (to(x, y) for x, y in
                                                        list(zip(xs, ys))[::step]))
        parts.append(f"<polyline points='{line}' fill='none' stroke='{COLOURS[i % 10]}' "
                     f"stroke-width='1.5'><title>{html.escape(str(label))}</title></polyline>")
    hx, hy = to(0.0, 0.0)
    parts.append(f"<path d='M{hx:.1f},{hy - 5:.1f} l4,8 h-8 z' fill='#000'><title>home"
                 f"</title></path>")
    return (f"<svg width='{size}' height='{size}' viewBox='0 0 {size} {size}' "
            f"style='border:1px solid #ddd;background:#fff'>{''.join(parts)}"
            f"<text x='4' y='{size - 4}' font-size='10' fill='#777'>{span:.3g} m across</text>"
            f"</svg>")


def _box(title: str, left: str, svg: str) -> str:
    return (f"<div style='display:flex;gap:12px;align-items:flex-start'><div><b>"
            f"{html.escape(title)}</b>{left}</div>{svg}</div>")


def flight_html(result) -> str:
    """A FlightResult: drone, end, KPIs, budgets and the path."""
    scen = result.scenario or {}
    drone = (scen.get("drone") or {}).get("name", "?") if isinstance(scen.get("drone"), dict) \
        else scen.get("drone", "?")
    tel = result.telemetry
    paths = {"path": (list(tel["x"]), list(tel["y"]))} if "x" in tel else {}
    cache = (getattr(result, "cache", None) or {}).get("status")
    title = (f"FlightResult: {drone}, {result.end_reason} after {fmt('flight_time_s', result.sim_time_s)}"
             + (f" (cache {cache})" if cache else ""))
    return _box(title, kpi_table(result.kpis) + budget_table(getattr(result, "verdicts", ())),
                path_svg(paths))


def fleet_html(result) -> str:
    """A FleetResult: fleet KPIs, one row per drone, and every drone's path."""
    drones = result.drones
    rows = [[f"<span style='color:{COLOURS[i % 10]}'>&#9632;</span> {html.escape(n)}",
             html.escape(str(r.end_reason)), fmt("flight_time_s", r.kpis.get("flight_time_s")),
             fmt("energy_total_j", r.kpis.get("energy_total_j"))]
            for i, (n, r) in enumerate(drones.items())]
    paths = {n: (list(r.telemetry["x"]), list(r.telemetry["y"])) for n, r in drones.items()
             if "x" in r.telemetry}
    left = (kpi_table({k: v for k, v in result.kpis.items() if k.startswith("fleet.")})
            + _table(rows, ["drone", "end", "flight time", "energy"])
            + budget_table(getattr(result, "verdicts", ())))
    return _box(f"FleetResult: {len(drones)} drones, {result.end_reason}", left, path_svg(paths))


def sweep_html(df, max_rows: int = 12) -> str:
    """A sweep's DataFrame: its settings, budgets and broken variants, the first rows."""
    a = df.attrs
    axes = list(a.get("axes") or [])
    budgets = a.get("budgets") or {}
    broken = int((~df["ok"].astype(bool)).sum()) if "ok" in df else 0
    cols = [c for c in axes + list(budgets) + ["ok"] if c in df]
    cols += [c for c in ("flight_time_s", "energy_total_j") if c in df and c not in cols]
    rows = [[html.escape(f"{r[c]:.4g}" if isinstance(r[c], float) and c in axes else
                         (str(r[c]) if c in axes or c == "ok" else fmt(c, r[c]))) for c in cols]
            for _, r in df.head(max_rows).iterrows()]
    more = f"<small>{len(df) - max_rows} more row(s)</small>" if len(df) > max_rows else ""
    budget_text = ", ".join(f"{k} {v}" for k, v in budgets.items()) or "none"
    head = (f"<b>sweep: {len(df)} variant(s) over {html.escape(', '.join(axes))} "
            f"({html.escape(str(a.get('method', 'grid')))})</b><br>budgets: "
            f"{html.escape(budget_text)}; <b style='color:{'#b3261e' if broken else '#176e2f'}'>"
            f"{broken} broken</b>")
    return head + _table(rows, cols) + more
