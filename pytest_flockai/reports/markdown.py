"""The Markdown job summary: ``--flockai-md PATH``, and appended to the file
named by ``GITHUB_STEP_SUMMARY`` when GitHub Actions sets it.

Sections: the headline (pytest's counts: ✅ when the run passed, ❌ only when it
failed), the scenario changes against the baseline, the budgets broken (those
broken where pytest expected it, in an xfail test, listed apart), the
regressions (one row per KPI family and test, biggest first), every test with
its outcome, then the KPI table (headline KPIs and every budgeted one).
"""

from __future__ import annotations

from . import files as _report
from . import summary as _s
from .compare import format_change


def _esc(text) -> str:
    """A table cell: no raw HTML (a test id such as ``test[<img src=x>]`` is shown, not
    rendered), no control characters, pipes escaped, one line."""
    text = str(text).replace("<", "&lt;")      # no tag can open; ">" alone is plain text
    return _report.printable(text.replace("|", "\\|").replace("\n", " "))


def _table(headers, rows) -> list[str]:
    out = ["| " + " | ".join(headers) + " |", "|" + "|".join("---" for _ in headers) + "|"]
    out += ["| " + " | ".join(_esc(c) for c in r) + " |" for r in rows]
    return out


def _folded(lines: list[str], n: int, what: str) -> list[str]:
    if n <= 12:
        return lines
    return [f"<details><summary>{what}</summary>", ""] + lines + ["", "</details>"]


def _budget_rows(rows) -> list[list]:
    return [[b["test"], b.get("flight") or "-", b["kpi"], b.get("budget"),
             b.get("actual_text") or _s.fmt(b["kpi"], b.get("actual")),
             b.get("margin_text") or b.get("margin"), b["outcome"]] for b in rows]


def _budgets(doc) -> list[str]:
    broken, expected = _s.broken_budgets(doc), _s.expected_broken(doc)
    lines = [f"### Budgets broken ({len(broken)})", ""]
    head = ["test", "flight", "KPI", "budget", "actual", "margin", "test outcome"]
    if broken:
        lines += _table(head, _budget_rows(broken))
    else:
        lines.append(f"None: {len(_s.budgets(doc)) - len(expected)} budget(s) hold.")
    if expected:
        lines += ["", f"Broken where pytest expected it (xfail, or a check the test expected "
                      f"to fail): {len(expected)}", ""]
        lines += _table(head, _budget_rows(expected))
    return lines


def _regressions(doc, base_scenarios) -> list[str]:
    groups, causes = _s.regression_groups(doc, base_scenarios)
    lines = []
    if causes:
        lines += ["### Scenario changes against the baseline", ""]
        lines += _table(["change", "tests"],
                        [[c, len(t)] for c, t in sorted(causes.items(), key=lambda kv: -len(kv[1]))])
        lines.append("")
    lines += [f"### Regressions against the baseline ({len(groups)})", ""]
    if groups:
        lines += _table(["cause", "test", "KPI family", "flights", "baseline", "actual", "change",
                         "better"],
                        [[g.cause or "-", g.test, g.family + (f" (x{g.count})" if g.count > 1 else ""),
                          len(g.flights), _s.fmt(g.worst.kpi, g.worst.base),
                          _s.fmt(g.worst.kpi, g.worst.new), format_change(g.worst),
                          g.worst.better] for g in groups])
    else:
        base = (doc.get("options") or {}).get("baseline")
        lines.append("None." if base else "No baseline given (--flockai-baseline).")
    return lines


def _tests(doc) -> list[str]:
    tests = doc.get("tests") or []
    rows = [[t["nodeid"], t.get("outcome"), len(t.get("flights") or ()),
             sum(b.get("verdict") != "pass" for b in t.get("budgets") or ()),
             len(t.get("budgets") or ())] for t in tests]
    lines = [f"### Tests ({len(tests)})", ""]
    return lines + _folded(_table(["test", "outcome", "flights", "budgets broken", "budgets"],
                                  rows), len(rows), "every test")


def job_summary(doc: dict, *, title: str = "pytest-flockai",
                base_scenarios: dict | None = None) -> str:
    """The summary of a ``pytest-flockai/1`` report as GitHub-flavoured Markdown."""
    lines = [f"## {title}: {'✅' if _s.ok(doc) else '❌'} {_s.counts(doc)}", "",
             _s.headline(doc).split("; ", 1)[-1], ""]
    if doc.get("interrupted"):
        lines += ["**The run was interrupted**: the tables are partial.", ""]
    lines += _regressions(doc, base_scenarios) + [""] + _budgets(doc) + [""] + _tests(doc)
    rows = _s.flights(doc)
    cols = _s.kpi_columns(doc, limit=8)
    lines += ["", f"### KPIs ({len(rows)} flight(s))", ""]
    if rows:
        lines += _folded(_table(["test", "flight"] + cols,
                                [[r["test"], r["flight"] + (" (cached)" if r["cache"] == "hit"
                                                            else "")]
                                 + [_s.fmt(k, r["kpis"].get(k)) for k in cols] for r in rows]),
                         len(rows), "KPI table")
    return "\n".join(lines) + "\n"
