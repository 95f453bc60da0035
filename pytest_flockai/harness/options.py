"""Command-line and ini options of the plugin (each option also an ini key)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

OPTIONS = [
    # (name, metavar, help)
    ("json", "PATH", "write a JSON report of every flight, KPI and budget (schema "
                     "pytest-flockai/1) to PATH, also when tests fail"),
    ("save", "PATH", "save the KPIs of this run as a baseline file at PATH"),
    ("baseline", "PATH", "compare each test's KPIs with the baseline file PATH (from "
                         "--flockai-save or --flockai-json); a test fails when a KPI is "
                         "worse than its baseline by more than --flockai-max-regression"),
    ("max-regression", "PCT", "largest allowed regression against the baseline, in percent "
                              "of the baseline value, in each KPI's better direction "
                              "(default: 5)"),
    ("abs-tol", "KPI=VALUE,...", "absolute tolerance per KPI in its SI unit (e.g. "
                                 "energy_total_j=5,cpu_utilization=0.001): a change no larger "
                                 "is never a regression; default: the KPI registry's"),
    ("artifacts", "DIR", "write each flight's telemetry (CSV) and result (JSON) under "
                         "DIR/<test nodeid>/"),
    ("sweep-executor", "ADDRESS", "fly the variants of @pytest.mark.flockai_sweep on the Dask "
                                  "scheduler at ADDRESS (tcp://host:8786; needs "
                                  "pytest-flockai[dask]) instead of this machine's processes; a "
                                  "marker's own executor= wins"),
    ("missing-baseline", "{warn,fail}", "what a test with flights but no entry in the "
                                       "--flockai-baseline file (or a flight the entry does "
                                       "not name) does: warn (default: noted in the terminal "
                                       "and the JSON report) or fail"),
]
#: the options whose value is a path (also safe in the space form, see rootdir.py)
PATH_OPTIONS = ("json", "save", "baseline", "artifacts")
MISSING_BASELINE = ("warn", "fail")
DEFAULT_MAX_REGRESSION = 5.0


def add_options(parser) -> None:
    group = parser.getgroup("flockai", "pytest-flockai: simulated drone flights and KPI budgets")
    for name, metavar, help_ in OPTIONS:
        dest = "flockai_" + name.replace("-", "_")
        group.addoption(f"--flockai-{name}", dest=dest, metavar=metavar, default=None,
                        help=help_)
        parser.addini(dest, f"{help_} (ini form of --flockai-{name})", type="string", default="")


def path_dests() -> list[str]:
    return ["flockai_" + n for n in PATH_OPTIONS]


def option(config, name: str):
    """(value, is_from_ini) of an option: the command line wins over the ini file."""
    dest = "flockai_" + name.replace("-", "_")
    v = config.getoption(dest, None)
    if v not in (None, ""):
        return v, False
    v = config.getini(dest)
    return (v if v not in (None, "") else None), True


def path_option(config, name: str) -> Path | None:
    """A path option, relative to the ini file (ini) or the invocation folder."""
    if config.getoption("flockai_" + name.replace("-", "_"), None) == "":
        raise pytest.UsageError(f"pytest-flockai: --flockai-{name} = '' is not allowed; "
                                f"expected a path")
    v, from_ini = option(config, name)
    if v is None:
        return None
    p = Path(os.path.expanduser(str(v)))
    if not p.is_absolute():
        if from_ini and config.inipath is not None:
            base = config.inipath.parent
        else:
            base = config.invocation_params.dir
        p = base / p
    return p
