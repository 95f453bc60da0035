"""The Markdown job summary: ``--flockai-md PATH``, and appended to the file
named by ``GITHUB_STEP_SUMMARY`` when GitHub Actions sets it.

Sections: the counts (and the flight cache), the budgets broken, the
regressions against the baseline, then the KPI table (headline KPIs and every
budgeted one, one row per flight).
"""

from __future__ import annotations

from .. import report as _report
from . import summary as _s


def _esc(text) -> str:
    """A table cell: no raw HTML (a test id such as ``test[<img src=x>]`` is shown, not
    rendered), no control characters, pipes escaped, one line."""
    text = str(text).replace("<", "&lt;")      # no tag can open; ">" alone is plain text
    return _report.printable(text.replace("|", "\\|").replace("\n", " "))


def _table(headers, rows) -> list[str]:
    out = ["| " + " | ".join(headers) + " |", "|" + "|".join("---" for _ in headers) + "|"]
    out += ["| " + " | ".join(_esc(c) for c in r) + " |" for r in rows]
    return out


def job_summary(doc: dict, *, title: str = "pytest-flockai") -> str:
    """The summary of a ``pytest-flockai/1`` report as GitHub-flavoured Markdown."""
    broken = _s.broken_budgets(doc)
    regs = _s.regressions(doc)
    status = "broken" if broken or regs or doc.get("summary", {}).get("failed") else "ok"
    lines = [f"## {title}: {'❌' if status == 'broken' else '✅'} {_s.counts(doc)}", ""]
    cached = [r for r in _s.flights(doc) if r["cache"] == "hit"]
    if cached:
        lines += [f"{len(cached)} flight(s) came from the flight cache.", ""]
    if doc.get("interrupted"):
        lines += ["**The run was interrupted**: the tables are partial.", ""]
    lines += [f"### Budgets broken ({len(broken)})", ""]
    if broken:
        lines += _table(["test", "flight", "KPI", "budget", "actual", "margin"],
                        [[b["test"], b.get("flight"), b["kpi"], b.get("budget"),
                          b.get("actual_text") or _s.fmt(b["kpi"], b.get("actual")),
                          b.get("margin_text") or b.get("margin")] for b in broken])
    else:
        lines.append(f"None: {len(_s.budgets(doc))} budget(s) hold.")
    lines += ["", f"### Regressions against the baseline ({len(regs)})", ""]
    if regs:
        lines += _table(["test", "flight", "KPI", "baseline", "actual", "change", "better"],
                        [[r["test"], r["flight"], r["kpi"], _s.fmt(r["kpi"], r["baseline"]),
                          _s.fmt(r["kpi"], r["actual"]), _s.fmt_pct(r.get("change_pct")),
                          r.get("better")] for r in regs])
    else:
        base = (doc.get("options") or {}).get("baseline")
        lines.append("None." if base else "No baseline given (--flockai-baseline).")
    rows = _s.flights(doc)
    cols = _s.kpi_columns(doc, limit=8)
    lines += ["", f"### KPIs ({len(rows)} flight(s))", ""]
    if rows:
        lines += ["<details><summary>KPI table</summary>", ""] if len(rows) > 12 else []
        lines += _table(["test", "flight"] + cols,
                        [[r["test"], r["flight"] + (" (cached)" if r["cache"] == "hit" else "")]
                         + [_s.fmt(k, r["kpis"].get(k)) for k in cols] for r in rows])
        lines += ["", "</details>"] if len(rows) > 12 else []
    return "\n".join(lines) + "\n"
