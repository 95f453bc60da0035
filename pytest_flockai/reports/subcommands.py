"""The ``flockai compare`` and ``flockai history`` subcommands (``cli.py`` adds them)."""

from __future__ import annotations

import sys
from pathlib import Path

from ..errors import close_matches
from . import compare as _compare
from . import files as _report
from . import history as _history


def add_parsers(sub) -> None:
    c = sub.add_parser("compare", help="KPI deltas between two runs; exit 1 on a regression")
    c.add_argument("base", type=Path, help="the base run: a --flockai-json report or baseline")
    c.add_argument("new", type=Path, help="the new run: a --flockai-json report or baseline")
    c.add_argument("--threshold", default="5%",
                   help="largest allowed regression, percent of the base value (default 5%%)")
    c.add_argument("--abs-tol", action="append", default=[], metavar="KPI=VALUE",
                   help="absolute tolerance of a KPI (or KPI family) in its SI unit, over the "
                        "registry's (kpis.abs_tolerance); repeatable, e.g. energy_total_j=5")
    c.add_argument("--all", action="store_true", help="show every regression row and every "
                                                      "changed KPI")
    c.add_argument("--json", type=Path, default=None, help="also write the deltas as JSON")
    h = sub.add_parser("history", help="a KPI across the runs kept by --flockai-history")
    h.add_argument("directory", type=Path)
    h.add_argument("--kpi", required=True, help="the KPI, e.g. endurance_s")
    h.add_argument("--test", default=None, help="only tests whose node id contains this")
    h.add_argument("--plot", type=Path, default=None, help="draw the trend to this PNG")


def run(a) -> int | None:
    """The exit status of a compare/history command, None for other commands."""
    if a.cmd == "compare":
        return _compare_cmd(a)
    if a.cmd == "history":
        return _history_cmd(a)
    return None


def _compare_cmd(a) -> int:
    try:
        threshold = _compare.parse_threshold(a.threshold)
    except ValueError:
        print(f"flockai compare: --threshold = {_report.printable(repr(a.threshold))} is not "
              f"allowed; expected a percentage >= 0, e.g. 5%", file=sys.stderr)
        return 2
    try:
        abs_tol = _compare.parse_abs_tol(a.abs_tol)
    except ValueError as exc:
        print(_report.printable(f"flockai compare: --abs-tol: {exc}"), file=sys.stderr)
        return 2
    if a.json is not None:
        _report.check_writable(a.json, "flockai compare --json")
    cmp = _compare.compare_files(a.base, a.new, threshold, abs_tol=abs_tol)   # ReportError: 2
    print(_report.printable(_compare.render(cmp, show_all=a.all), newlines=True))
    if a.json is not None:
        _report.write_json_atomic(a.json, {"threshold_pct": threshold, "abs_tol": abs_tol,
                                           "causes": cmp.causes,
                                           "deltas": [d.to_dict() for d in cmp.deltas],
                                           "only_base": cmp.only_base, "only_new": cmp.only_new})
    return 1 if cmp.regressions else 0


def _history_cmd(a) -> int:
    if a.plot is not None:
        if a.plot.suffix.lower() != ".png":
            raise _report.ReportError(f"flockai history --plot {str(a.plot)!r}: expected a "
                                      f"file path ending in .png")
        _report.check_writable(a.plot, "flockai history --plot")
    skipped: list = []
    runs = _history.load(a.directory, skipped)
    for path, why in skipped:
        print(_report.printable(f"flockai history: WARNING: skipped {path}: {why}"),
              file=sys.stderr)
    if runs and not _history.series(runs, a.kpi, a.test):
        raise _report.ReportError(_missing_kpi(runs, a))
    print(_report.printable(_history.render(runs, a.kpi, a.test), newlines=True))
    if a.plot is not None:
        _history.plot(runs, a.kpi, a.plot, a.test)
        print(_report.printable(f"trend drawn to {a.plot}"))
    return 0


def _missing_kpi(runs: list[dict], a) -> str:
    """Why ``--kpi`` (with ``--test``) has no series: a misspelling, or a test filter."""
    where = f" in a test matching --test {a.test!r}" if a.test else ""
    known = sorted({k for r in runs for nodeid, flights in r["tests"].items()
                    if a.test is None or a.test in nodeid for kp in flights.values() for k in kp})
    shown = ", ".join(known[:12]) + (f" and {len(known) - 12} more" if len(known) > 12 else "")
    return (f"--kpi {a.kpi!r}: no run in {str(a.directory)!r} has it{where}"
            f"{close_matches(a.kpi, known)}; KPIs there: {shown or 'none'}")
