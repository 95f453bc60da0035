"""The self-contained HTML dashboard of a run (``--flockai-html PATH``).

One file, no network: the style, a small table-sorting script and every
picture (flight path and energy breakdown per flight, pictures a test
attaches such as robustness maps) are inside it, pictures as ``data:`` URIs.
Sections: the counts; the budgets with their margins (sortable, broken ones
first); the deltas against the baseline when one was given; the KPI table
(one row per flight, sortable by any KPI); the pictures of each test.

Sorting: click a column header; ``page.html#sort=<table id>:<column>:<asc|desc>``
opens the page sorted (how the browser test checks it).
"""

from __future__ import annotations

import hashlib
import html as _html
import math

from .._io import atomic_write
from . import ml_gallery as _ml_gallery
from . import summary as _s
from .compare import compare as _compare
from .compare import format_change

_CSS = """
body{font:14px/1.4 system-ui,sans-serif;margin:24px;color:#222;background:#fafafa}
h1{font-size:22px}h2{font-size:18px;margin-top:28px}h3{font-size:15px}
table{border-collapse:collapse;background:#fff;margin:8px 0;font-variant-numeric:tabular-nums}
th,td{border:1px solid #ddd;padding:4px 8px;text-align:left;white-space:nowrap}
th{background:#eef;cursor:pointer;user-select:none}th.asc:after{content:" \\25B2"}
th.desc:after{content:" \\25BC"}
tr.fail td,td.fail{background:#fde2e2}tr.pass td.verdict,td.better{color:#176e2f}
td.regression{background:#fde2e2;font-weight:bold}td.worse{color:#a35b00}
.scroll{overflow:auto;max-width:100%;max-height:420px}
th{position:sticky;top:0}.ok{color:#176e2f}.bad{color:#b3261e}
.pics figure{display:inline-block;width:48%;margin:4px;vertical-align:top}
.pics img{width:100%;border:1px solid #ddd;background:#fff}
.muted{color:#777}
"""

_JS = """
function sortTable(table, col, dir){
  const body = table.tBodies[0]; const rows = Array.from(body.rows);
  const key = r => { const c = r.cells[col]; const v = c.dataset.sort;
    if (v !== undefined && v !== "") return parseFloat(v);
    return c.textContent.trim().toLowerCase(); };
  rows.sort((a, b) => { const x = key(a), y = key(b);
    const nx = typeof x === "number", ny = typeof y === "number";
    let r = nx && ny ? x - y : nx ? -1 : ny ? 1 : (x < y ? -1 : x > y ? 1 : 0);
    return dir === "desc" ? -r : r; });
  rows.forEach(r => body.appendChild(r));
  Array.from(table.tHead.rows[0].cells).forEach((th, i) => {
    th.classList.remove("asc", "desc"); if (i === col) th.classList.add(dir); });
  table.dataset.sorted = table.tHead.rows[0].cells[col].dataset.col + ":" + dir;
}
document.querySelectorAll("table.sortable").forEach(t => {
  Array.from(t.tHead.rows[0].cells).forEach((th, i) => th.addEventListener("click", () =>
    sortTable(t, i, th.classList.contains("asc") ? "desc" : "asc")));
});
const m = location.hash.match(/^#sort=([\\w-]+):([^:]+):(asc|desc)$/);
if (m) { const t = document.getElementById(m[1]);
  if (t) { const ths = Array.from(t.tHead.rows[0].cells);
    const i = ths.findIndex(th => th.dataset.col === decodeURIComponent(m[2]));
    if (i >= 0) sortTable(t, i, m[3]); } }
"""


def _e(x) -> str:
    return _html.escape(str(x), quote=True)


def _num(v) -> str:
    try:
        f = float(v)
    except (TypeError, ValueError):
        return ""
    return repr(f) if math.isfinite(f) else ""


def _short(v) -> str:
    n = _num(v)
    return f"{float(n):.4g}" if n else "n/a"


def _table(tid: str, headers: list[str], rows: list[tuple[list, str]]) -> str:
    """rows: ([(text, sort value or None, css class or ""), ...], row class)."""
    head = "".join(f'<th data-col="{_e(h)}">{_e(h)}</th>' for h in headers)
    body = []
    for cells, cls in rows:
        tds = "".join(f'<td data-sort="{_e(s if s is not None else "")}"'
                      f'{f" class={chr(34)}{c}{chr(34)}" if c else ""}>{_e(t)}</td>'
                      for t, s, c in cells)
        body.append(f'<tr class="{cls}">{tds}</tr>')
    return (f'<div class="scroll"><table id="{tid}" class="sortable"><thead><tr>{head}</tr></thead>'
            f'<tbody>{"".join(body)}</tbody></table></div>')


def _budgets(doc) -> str:
    rows = []
    for b in sorted(_s.budgets(doc), key=lambda b: (b.get("verdict") == "pass", b["test"])):
        v = b.get("verdict")
        rows.append(([(b["test"], None, ""), (b.get("flight"), None, ""), (b["kpi"], None, ""),
                      (b.get("budget"), None, ""),
                      (b.get("actual_text") or _s.fmt(b["kpi"], b.get("actual")),
                       _num(b.get("actual")), ""),
                      (b.get("margin_text") or _short(b.get("margin")), _num(b.get("margin")), ""),
                      (v, None, "verdict")], "pass" if v == "pass" else "fail"))
    if not rows:
        return '<p class="muted">No test has a kpi budget.</p>'
    return _table("budgets", ["test", "flight", "KPI", "budget", "actual", "margin", "verdict"],
                  rows)


def _deltas(doc, baseline: dict | None, threshold_pct: float) -> str:
    if not baseline:
        return '<p class="muted">No baseline given (--flockai-baseline).</p>'
    current = {t["nodeid"]: {f["name"]: f["kpis"] for f in t.get("flights", ())}
               for t in doc.get("tests", ())}
    cmp = _compare(baseline, current, threshold_pct)
    rows = []
    for d in cmp.deltas:
        if d.better is None or d.status in ("n/a", "same"):
            continue
        rows.append(([(d.test, None, ""), (d.flight, None, ""), (d.kpi, None, ""),
                      (_s.fmt(d.kpi, d.base), _num(d.base), ""),
                      (_s.fmt(d.kpi, d.new), _num(d.new), ""),
                      (format_change(d), _num(d.change_pct), ""), (d.better, None, ""),
                      (d.status, None, d.status)], ""))
    if not rows:
        return '<p class="muted">No KPI changed against the baseline.</p>'
    return _table("deltas", ["test", "flight", "KPI", "base", "new", "change", "better",
                             "status"], rows)


def _kpis(doc) -> str:
    flights = _s.flights(doc)
    if not flights:
        return '<p class="muted">No flights.</p>'
    cols = _s.kpi_columns(doc)
    rows = []
    for r in flights:
        cells = [(r["test"], None, ""), (r["flight"], None, ""), (r["outcome"], None, ""),
                 ("cache" if r["cache"] == "hit" else "flown", None, "")]
        cells += [(_s.fmt(k, r["kpis"].get(k)), _num(r["kpis"].get(k)), "") for k in cols]
        rows.append((cells, "fail" if r["outcome"] in ("failed", "error") else ""))
    headers = ["test", "flight", "outcome", "source"] + cols
    return _table("kpis", headers, rows)


def _pictures(doc, pictures: dict) -> str:
    """Each test's pictures. A picture already shown for an earlier test (a shared fixture
    flight's path, seen by every test that uses it) is embedded once and linked after."""
    out, seen = [], {}
    for t in doc.get("tests", ()):
        pics = pictures.get(t["nodeid"]) or []
        if not pics:
            continue
        figs = []
        for p in pics:
            key = hashlib.sha256(p["data"].encode()).hexdigest()[:16]
            cap = f'<figcaption class="muted">{_e(p["title"])}</figcaption>'
            if key in seen:
                figs.append(f'<figure class="same"><a href="#pic-{key}">same picture as '
                            f'{_e(seen[key])}</a>{cap}</figure>')
                continue
            seen[key] = t["nodeid"]
            if "gallery" in p:                          # a detection task's worst frame
                figs.append(_ml_gallery.figure(p, key))
                continue
            figs.append(f'<figure id="pic-{key}"><img alt="{_e(p["title"])}" '
                        f'src="data:{_e(p.get("mime", "image/png"))};base64,{p["data"]}">'
                        f'{cap}</figure>')
        out.append(f'<h3>{_e(t["nodeid"])}</h3><div class="pics">{"".join(figs)}</div>')
    return "".join(out) or '<p class="muted">No pictures (they need matplotlib).</p>'


def dashboard(doc: dict, *, pictures: dict | None = None, baseline: dict | None = None,
              threshold_pct: float = 5.0, title: str = "pytest-flockai") -> str:
    """The dashboard of a ``pytest-flockai/1`` report as one HTML string.

    pictures: ``{nodeid: [{"title": str, "data": base64 PNG}]}``; baseline:
    ``{nodeid: {flight: {kpi: value}}}`` (``report.load_baseline``)."""
    broken = _s.broken_budgets(doc)
    regs = _s.regressions(doc)
    ok = not broken and not regs and not doc.get("summary", {}).get("failed")
    env = (doc.get("environment") or {}).get("packages", {})
    cached = sum(r["cache"] == "hit" for r in _s.flights(doc))
    parts = [
        "<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\">",
        f"<title>{_e(title)}</title><style>{_CSS}</style></head><body>",
        f"<h1>{_e(title)}</h1>",
        f'<p id="status" class="{"ok" if ok else "bad"}">{_e(_s.counts(doc))}; '
        f"{len(broken)} budget(s) broken, {len(regs)} regression(s)"
        f"{f'; {cached} flight(s) from the cache' if cached else ''}</p>",
        f'<p class="muted">{_e(doc.get("created", ""))} · pytest-flockai '
        f'{_e(env.get("pytest-flockai", "?"))} · MuJoCo {_e(env.get("mujoco", "?"))}</p>',
        "<h2>Budgets</h2>", _budgets(doc),
        "<h2>Against the baseline</h2>", _deltas(doc, baseline, threshold_pct),
        "<h2>KPIs</h2>", _kpis(doc),
        "<h2>Pictures</h2>", _pictures(doc, pictures or {}),
        f"<script>{_JS}</script></body></html>",
    ]
    return "\n".join(parts)


def write(path, doc: dict, **kw) -> None:
    """Write the dashboard atomically."""
    text = dashboard(doc, **kw)
    atomic_write(path, lambda fh: fh.write(text))
