"""The self-contained HTML dashboard (``--flockai-html PATH``).

One file, no network: the style, the script (``html_assets.py``) and every
picture (flight paths, energy breakdowns, the pictures a test attaches, such as
robustness maps) are inside it, pictures as ``data:`` URIs.

Read top down, at 1280 px: the headline (pytest's counts, green when the run
passed, red only when it failed), a band of counts (passed, failed, broken
budgets, regressions, cache hits, the slowest flights), filters by outcome,
then what needs attention (the scenario changes against the baseline, the
budgets broken, the regressions one row per KPI family and test), then every
test, the KPIs, every budget, the deltas, and the detail of each test with its
pictures. Every table puts its verdict first and scrolls sideways in its box
when it is wider than the page.

Sections are the list ``SECTIONS`` of ``(title, render(page) -> html)``: a
module adds its own with ``add_section`` (the ML gallery does).

Sorting: click a column header; ``page.html#sort=<table id>:<column>:<asc|desc>``
opens the page sorted, ``page.html#filter=<outcome>`` filtered (how the browser
test checks it).
"""

from __future__ import annotations

import hashlib
import html as _html
import math
from dataclasses import dataclass, field

from .._io import atomic_write
from . import ml_gallery as _ml_gallery
from . import summary as _s
from .compare import compare as _compare
from .compare import family, format_change
from .html_assets import CSS, JS


@dataclass
class Page:
    """What the sections render from."""

    doc: dict
    pictures: dict = field(default_factory=dict)      # nodeid -> [{"title", "data"}]
    baseline: dict | None = None
    threshold_pct: float = 5.0
    base_scenarios: dict | None = None
    abs_tol: dict | None = None
    pictures_missing: str | None = None              # why the flights have no pictures


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


def _breakable(nodeid) -> str:
    """A test id that wraps after its ``::``, ``/`` and ``[`` rather than inside a name."""
    out = _e(nodeid)
    for sep in ("::", "/", "["):
        out = out.replace(sep, sep + "<wbr>")
    return out


def _cell(text, sort=None, cls: str = "") -> tuple:
    return (text, sort, cls)


def table(tid: str, headers: list[str], rows: list[tuple[list, str, str]]) -> str:
    """A sortable table in a box that scrolls sideways. rows: ([cells], row class,
    outcome for the filters or ""); a cell is (text, sort value or None, css class)."""
    head = "".join(f'<th data-col="{_e(h)}">{_e(h)}</th>' for h in headers)
    body = []
    for cells, cls, outcome in rows:
        tds = "".join(f'<td data-sort="{_e(s if s is not None else "")}"'
                      f'{f" class={chr(34)}{c}{chr(34)}" if c else ""}>'
                      f'{_breakable(t) if c == "id" else _e(t)}</td>' for t, s, c in cells)
        data = f' data-outcome="{_e(outcome)}"' if outcome else ""
        body.append(f'<tr class="{cls}"{data}>{tds}</tr>')
    return (f'<div class="scroll"><table id="{tid}" class="sortable"><thead><tr>{head}</tr>'
            f'</thead><tbody>{"".join(body)}</tbody></table></div>')


def _muted(text: str) -> str:
    return f'<p class="muted">{_e(text)}</p>'


def _outcomes(doc) -> dict:
    return {t["nodeid"]: t.get("outcome", "") for t in doc.get("tests", ())}


# -- the header ---------------------------------------------------------------------------
def _card(label: str, value, cls: str = "", note: str = "") -> str:
    small = f"<small>{_e(note)}</small>" if note else ""
    return f'<div class="card {cls}" data-card="{_e(label)}"><b>{_e(value)}</b>{_e(label)}{small}</div>'


def _band(page: Page) -> str:
    doc = page.doc
    s = doc.get("summary", {})
    groups, _ = _s.regression_groups(doc, page.base_scenarios)
    broken, expected = _s.per_test(_s.broken_budgets(doc)), _s.per_test(_s.expected_broken(doc))
    listed = _s.flights(doc)
    distinct = _s.distinct_flights(listed)
    hits = sum(r["cache"] == "hit" for r in distinct)
    shared = f"; {len(listed)} listed by the tests" if len(listed) != len(distinct) else ""
    failing = sum(s.get(k, 0) for k in _s.FAILING)
    cards = [_card("passed", s.get("passed", 0), "ok"),
             _card("failed", failing, "bad" if failing else ""),
             _card("xfailed", s.get("xfailed", 0), "warn" if s.get("xfailed") else ""),
             _card("skipped", s.get("skipped", 0)),
             _card("budgets broken", len(broken), "bad" if broken else "",
                   f"+{len(expected)} expected" if expected else ""),
             _card("regressions", len(groups), "bad" if groups else "", "KPI families"),
             _card("flights", len(distinct), "", f"{hits} from the cache{shared}")]
    slow = _s.slowest(doc)
    if slow:
        cards.append(_card("slowest flights", f"{slow[0]['wall_time_s']:.1f} s", "",
                           "; ".join(f"{r['test'].split('::')[-1]} {r['wall_time_s']:.1f} s"
                                     for r in slow)))
    return f'<div class="band" id="band">{"".join(cards)}</div>'


def _filters(doc) -> str:
    present = [o for o in _s.OUTCOMES if doc.get("summary", {}).get(o)]
    buttons = "".join(f'<button data-filter="{o}">{o}</button>' for o in ["all"] + present)
    return f'<div class="filters">show: {buttons}</div>'


def header(page: Page, title: str) -> str:
    doc = page.doc
    env = (doc.get("environment") or {}).get("packages", {})
    return "".join([
        f"<h1>{_e(title)}</h1>",
        f'<p id="status" class="{"ok" if _s.ok(doc) else "bad"}">{_e(_s.headline(doc))}</p>',
        _band(page),
        f'<p class="muted">{_e(doc.get("created", ""))} · pytest-flockai '
        f'{_e(env.get("pytest-flockai", "?"))} · MuJoCo {_e(env.get("mujoco", "?"))} · exit '
        f'status {_e(doc.get("exitstatus", "?"))}</p>',
        _filters(doc)])


# -- what needs attention --------------------------------------------------------------------
def scenario_changes(page: Page) -> str:
    _, causes = _s.regression_groups(page.doc, page.base_scenarios)
    if not causes:
        return ""
    rows = [([_cell(c, None, "wrap"), _cell(len(t), len(t)), _cell(", ".join(
        x.split("::")[-1] for x in t[:4]) + (" ..." if len(t) > 4 else ""), None, "wrap")], "", "")
            for c, t in sorted(causes.items(), key=lambda kv: -len(kv[1]))]
    return table("scenario", ["change", "tests", "which"], rows)


def _budget_row(b: dict) -> tuple:
    state = b["state"]
    return ([_cell(state, None, f"v s-{state}"), _cell(b["test"], None, "id"),
             _cell(b.get("flight") or "-"), _cell(b["kpi"]), _cell(b.get("budget")),
             _cell(b.get("actual_text") or _s.fmt(b["kpi"], b.get("actual")), _num(b.get("actual"))),
             _cell(b.get("margin_text") or _short(b.get("margin")), _num(b.get("margin"))),
             _cell(b.get("source") or "marker")],
            "bad" if state == "broken" else "", b.get("outcome") or "")


_BUDGET_HEAD = ["verdict", "test", "flight", "KPI", "budget", "actual", "margin", "from"]


def broken_budgets(page: Page) -> str:
    rows = _s.broken_budgets(page.doc) + _s.expected_broken(page.doc)
    if not rows:
        return _muted(f"None: {len(_s.budgets(page.doc))} budget(s) hold.")
    return table("broken", _BUDGET_HEAD, [_budget_row(b) for b in rows])


def regressions(page: Page) -> str:
    groups, _ = _s.regression_groups(page.doc, page.base_scenarios)
    if not groups:
        return _muted("None." if page.baseline else "No baseline given (--flockai-baseline).")
    outcomes = _outcomes(page.doc)
    rows = []
    for g in groups:
        d = g.worst
        rows.append(([_cell(format_change(d), _num(d.change_pct), "v s-regression"),
                      _cell(g.family + (f" (x{g.count})" if g.count > 1 else "")),
                      _cell(g.test, None, "id"), _cell(len(g.flights), len(g.flights)),
                      _cell(_s.fmt(d.kpi, d.base), _num(d.base)),
                      _cell(_s.fmt(d.kpi, d.new), _num(d.new)), _cell(d.better),
                      _cell(g.cause or "-", None, "wrap")], "bad", outcomes.get(g.test, "")))
    return table("regressions", ["change", "KPI family", "test", "flights", "baseline", "actual",
                                 "better", "cause"], rows)


# -- every test, KPI and budget -----------------------------------------------------------------
def tests(page: Page) -> str:
    rows = []
    for t in page.doc.get("tests", ()):
        o = t.get("outcome", "")
        bs = t.get("budgets") or []
        fl = t.get("flights") or []
        broken = sum(b.get("verdict") != "pass" for b in bs)
        fams = {family(r["kpi"]) for r in t.get("regressions") or ()}
        rows.append(([_cell(o, None, f"v s-{o}"), _cell(t["nodeid"], None, "id"),
                      _cell(len(fl), len(fl)), _cell(f"{broken}/{len(bs)}" if bs else "-", broken),
                      _cell(len(fams), len(fams)),
                      _cell(sum((f.get("cache") or {}).get("status") == "hit" for f in fl)),
                      _cell((t.get("message") or t.get("error") or "").split("\n")[0][:160],
                            None, "wrap")],
                     "bad" if o in _s.FAILING else "", o))
    if not rows:
        return _muted("No test ran.")
    return table("tests", ["outcome", "test", "flights", "budgets broken", "regressions",
                           "cached", "message"], rows)


#: KPI columns of the per-flight table (the headline KPIs, then the budgeted ones): the
#: table reads at 1280 px; every KPI is in "Every KPI", one row each
KPI_COLUMNS = 8


def _headline_cell(kpis: dict, k: str) -> tuple:
    """The flight's ``k``, or for a fleet its drones' ``<drone>.k`` as a range."""
    v = kpis.get(k)
    if v is not None:
        return _cell(_s.fmt(k, v), _num(v))
    per = sorted(x for kk, x in kpis.items() if "." in kk and family(kk) == k
                 and isinstance(x, (int, float)) and not math.isnan(x))
    if not per:
        return _cell(_s.fmt(k, None), None)
    text = _s.fmt(k, per[0]) if per[0] == per[-1] else \
        f"{_s.fmt(k, per[0])} to {_s.fmt(k, per[-1])} ({len(per)} drones)"
    return _cell(text, _num(per[-1]))


def kpi_table(page: Page) -> str:
    flights = _s.flights(page.doc)
    if not flights:
        return _muted("No flights.")
    cols = _s.kpi_columns(page.doc, limit=KPI_COLUMNS)
    rows = []
    for r in flights:
        o = r["outcome"]
        cells = [_cell(o, None, f"v s-{o}"), _cell(r["test"], None, "id"), _cell(r["flight"]),
                 _cell("cache" if r["cache"] == "hit" else "flown")]
        cells += [_headline_cell(r["kpis"], k) for k in cols]
        rows.append((cells, "bad" if o in _s.FAILING else "", o))
    more = len(_s.kpi_columns(page.doc)) - len(cols)
    note = _muted(f"{more} more KPI(s) per flight in Every KPI, one row each.") if more > 0 else ""
    return table("kpis", ["outcome", "test", "flight", "source"] + cols, rows) + note


def every_kpi(page: Page) -> str:
    """Every KPI of every flight, one row each (group: its task, drone or family)."""
    rows = []
    for r in _s.flights(page.doc):
        o = r["outcome"]
        for k, v in sorted(r["kpis"].items()):
            group = k.split(".", 1)[0] if "." in k else "flight"
            rows.append(([_cell(o, None, f"v s-{o}"), _cell(r["test"], None, "id"),
                          _cell(r["flight"]), _cell(group), _cell(k, None, "wrap"),
                          _cell(_s.fmt(k, v), _num(v))], "bad" if o in _s.FAILING else "", o))
    if not rows:
        return ""
    return (f"<details><summary>{len(rows)} values: open to read, sort or filter</summary>"
            + table("every-kpi", ["outcome", "test", "flight", "group", "KPI", "value"], rows)
            + "</details>")


def all_budgets(page: Page) -> str:
    rows = sorted(_s.budgets(page.doc), key=lambda b: (b["state"] == "pass", b["test"]))
    if not rows:
        return _muted("No test has a kpi budget.")
    return table("budgets", _BUDGET_HEAD, [_budget_row(b) for b in rows])


def deltas(page: Page) -> str:
    if not page.baseline:
        return _muted("No baseline given (--flockai-baseline).")
    doc = page.doc
    current = {t["nodeid"]: {f["name"]: f["kpis"] for f in t.get("flights", ())}
               for t in doc.get("tests", ())}
    cmp = _compare(page.baseline, current, page.threshold_pct, abs_tol=page.abs_tol)
    outcomes = _outcomes(doc)
    rows = []
    for d in cmp.deltas:
        if d.better is None or d.status in ("n/a", "same"):
            continue
        rows.append(([_cell(d.status, None, f"v s-{d.status}"), _cell(d.test, None, "id"),
                      _cell(d.flight), _cell(d.kpi), _cell(_s.fmt(d.kpi, d.base), _num(d.base)),
                      _cell(_s.fmt(d.kpi, d.new), _num(d.new)),
                      _cell(format_change(d), _num(d.change_pct)), _cell(d.better)],
                     "", outcomes.get(d.test, "")))
    if not rows:
        return _muted("No KPI changed against the baseline beyond its tolerance.")
    return table("deltas", ["status", "test", "flight", "KPI", "base", "new", "change",
                            "better"], rows)


# -- the detail of each test ---------------------------------------------------------------------
def details(page: Page) -> str:
    """Each test with its outcome, budgets and pictures. A picture already shown for an
    earlier test (a shared fixture flight's path) is embedded once and linked after."""
    out: list[str] = []
    seen: dict[str, str] = {}
    for t in page.doc.get("tests", ()):
        o = t.get("outcome", "")
        figs = []
        for p in page.pictures.get(t["nodeid"]) or []:
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
            figs.append(f'<figure id="pic-{key}"><img alt="{_e(p["title"])}" loading="lazy" '
                        f'src="data:{_e(p.get("mime", "image/png"))};base64,{p["data"]}">'
                        f'{cap}</figure>')
        bs = t.get("budgets") or []
        summary = (f'{len(t.get("flights") or ())} flight(s), '
                   f'{sum(b.get("verdict") != "pass" for b in bs)} of {len(bs)} budget(s) broken')
        msg = t.get("message") or t.get("error")
        summary += "".join(f"\npolicies: {line}" for line in _s.decisions(t))
        out.append(f'<section class="test" data-outcome="{_e(o)}"><h3><span class="s-{_e(o)}">'
                   f'{_e(o)}</span> {_e(t["nodeid"])}</h3><p class="muted">'
                   f'{_e(summary).replace(chr(10), "<br>")}</p>'
                   + (f"<pre>{_e(msg)}</pre>" if msg else "")
                   + (f'<div class="pics">{"".join(figs)}</div>' if figs else "") + "</section>")
    note = (f'<p class="muted" id="pictures-missing">{_e(page.pictures_missing)}</p>'
            if page.pictures_missing else "")
    return note + "".join(out) if out else _muted("No test ran.")


#: the page's sections, top down: (title, render(page) -> html); "" renders nothing
SECTIONS: list = [
    ("Scenario changes against the baseline", scenario_changes),
    ("Budgets broken", broken_budgets),
    ("Regressions against the baseline", regressions),
    ("Tests", tests),
    ("KPIs", kpi_table),
    ("Every KPI", every_kpi),
    ("Every budget", all_budgets),
    ("Every KPI change against the baseline", deltas),
    ("Detail per test", details),
]


def add_section(title: str, render, *, before: str = "Detail per test") -> None:
    """Add a section ``render(page) -> html`` to every dashboard, before ``before``
    (at the end when no section has that title); a title already there is replaced."""
    for i, (t, _) in enumerate(SECTIONS):
        if t == title:
            SECTIONS[i] = (title, render)
            return
    at = next((i for i, (t, _) in enumerate(SECTIONS) if t == before), len(SECTIONS))
    SECTIONS.insert(at, (title, render))


def dashboard(doc: dict, *, pictures: dict | None = None, baseline: dict | None = None,
              threshold_pct: float = 5.0, title: str = "pytest-flockai",
              base_scenarios: dict | None = None, abs_tol: dict | None = None,
              pictures_missing: str | None = None) -> str:
    """The dashboard of a ``pytest-flockai/1`` report as one HTML string.

    pictures: ``{nodeid: [{"title": str, "data": base64 PNG}]}``; baseline:
    ``{nodeid: {flight: {kpi: value}}}`` (``report.load_baseline``); base_scenarios:
    its scenario summaries (``compare.load_scenarios``); pictures_missing: why the
    flights have no pictures (shown above the detail per test)."""
    page = Page(doc, pictures or {}, baseline, threshold_pct, base_scenarios, abs_tol,
                pictures_missing)
    parts = ["<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\">",
             '<meta name="viewport" content="width=device-width, initial-scale=1">',
             f"<title>{_e(title)}</title><style>{CSS}</style></head><body>", header(page, title)]
    for name, render in SECTIONS:
        body = render(page)
        if body:
            slug = "".join(c if c.isalnum() else "-" for c in name.lower())
            parts.append(f'<h2 id="sec-{slug}">{_e(name)}</h2>{body}')
    parts.append(f"<script>{JS}</script></body></html>")
    return "\n".join(parts)


def write(path, doc: dict, **kw) -> None:
    """Write the dashboard atomically."""
    text = dashboard(doc, **kw)
    atomic_write(path, lambda fh: fh.write(text))
