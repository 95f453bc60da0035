"""Reports people look at, and comparisons across commits.

- ``compare``: ``flockai compare BASE.json NEW.json``: the scenario changes, then the
  regressions one row per KPI family and test, biggest first, grouped by cause, with a
  relative threshold and an absolute tolerance per KPI; exit status 1 on a regression;
- ``scenario``: what a flight was in a few words, and the difference between two runs;
- ``summary``: what the Markdown summary and the dashboard show (pytest's counts);
- ``history``: ``--flockai-history DIR`` keeps each run's KPIs with its git
  commit; ``flockai history DIR --kpi endurance_s`` prints (and draws) the trend;
- ``markdown``: the job summary (``--flockai-md PATH``, ``GITHUB_STEP_SUMMARY``);
- ``html``: the self-contained dashboard (``--flockai-html PATH``; ``html_assets``: its
  style and script; ``ml_gallery``: a detection task's worst frames);
- ``subcommands``: the ``flockai compare`` and ``flockai history`` subcommands;
- ``files``: the files the plugin writes: the JSON report, the baseline, the
  artifacts, and the text tables of the terminal summary;
- ``commands``: the old path of ``subcommands``, kept as a shim that warns once.

Everything here reads or writes the plain data of the JSON report; none of it needs
pytest (the plugin's side is ``harness/``).
"""

from importlib import import_module as _import_module
from typing import TYPE_CHECKING

if TYPE_CHECKING:      # what _PUBLIC imports on first use, spelled out for type checkers and docs
    from .compare import Comparison, classify
    from .compare import compare as compare_reports
    from .scenario import diff as scenario_diff
    from .scenario import summary as scenario_summary

#: public name -> (module, attribute): the reports' Python face, imported on first use
#: (the plugin loads this package in every run; the modules stay internal)
_PUBLIC = {"Comparison": (".compare", "Comparison"), "classify": (".compare", "classify"),
           "compare_reports": (".compare", "compare"), "scenario_diff": (".scenario", "diff"),
           "scenario_summary": (".scenario", "summary")}

__all__ = ["Comparison", "classify", "compare_reports", "scenario_diff", "scenario_summary"]


def __getattr__(name: str):
    if name not in _PUBLIC:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    module, attr = _PUBLIC[name]
    value = getattr(_import_module(module, __name__), attr)
    globals()[name] = value
    return value
