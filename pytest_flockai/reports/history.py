"""KPIs across commits: ``--flockai-history DIR`` and ``flockai history DIR``.

Each run (on the controller, at the end of the session) writes one file
``DIR/<UTC time>-<commit>.json`` (atomically; concurrent CI jobs never write
the same file)::

    {"schema": "pytest-flockai-history/1", "created": "2026-01-01T12:00:00+00:00",
     "commit": "0123abc..." or null, "dirty": false, "branch": "main" or null,
     "tests": {"<nodeid>": {"<flight>": {"<kpi>": value}}}}

The commit comes from ``FLOCKAI_COMMIT``, else ``GITHUB_SHA``, else ``git
rev-parse HEAD`` in the invocation folder (null outside a repository).
``flockai history DIR --kpi endurance_s`` prints one row per run and one
column per flight that has the KPI; ``--plot PNG`` draws the trend (needs
matplotlib).
"""

from __future__ import annotations

import datetime as _dt
import os
import re
import subprocess
from pathlib import Path

from .. import kpis as _kpis
from .._io import atomic_write
from . import files as _report

SCHEMA = "pytest-flockai-history/1"


def git_info(cwd) -> dict:
    """{"commit", "dirty", "branch"} of the repository at ``cwd`` (nulls outside one)."""
    commit = os.environ.get("FLOCKAI_COMMIT") or os.environ.get("GITHUB_SHA")
    branch = os.environ.get("GITHUB_REF_NAME")
    dirty = None
    try:
        if commit is None:
            commit = _git(cwd, "rev-parse", "HEAD")
            dirty = bool(_git(cwd, "status", "--porcelain", "--untracked-files=no"))
        if branch is None:
            branch = _git(cwd, "rev-parse", "--abbrev-ref", "HEAD")
    except (OSError, subprocess.SubprocessError):
        pass
    tag = None
    if commit:
        try:
            tag = _git(cwd, "describe", "--tags", "--exact-match", commit) or None
        except (OSError, subprocess.SubprocessError):
            tag = None
    return {"commit": commit or None, "dirty": dirty, "branch": branch or None, "tag": tag}


def _git(cwd, *args) -> str:
    out = subprocess.run(["git", *args], cwd=cwd, capture_output=True, text=True, timeout=10)
    if out.returncode != 0:
        raise subprocess.SubprocessError(out.stderr.strip())
    return out.stdout.strip()


def record(directory, entries: list[dict], cwd) -> Path:
    """Write this run's KPIs (per-test entries of the session) into ``directory``."""
    d = Path(directory)
    d.mkdir(parents=True, exist_ok=True)
    now = _dt.datetime.now(_dt.UTC)
    info = git_info(cwd)
    doc = {"schema": SCHEMA, "created": now.isoformat(timespec="seconds"), **info,
           "tests": _report.baseline_from_tests(entries)["tests"]}
    stamp = now.strftime("%Y%m%dT%H%M%S.%fZ")
    name = f"{stamp}-{(info['commit'] or 'nocommit')[:12]}.json"
    path = d / re.sub(r"[^A-Za-z0-9_.-]", "_", name)
    _report.write_json_atomic(path, doc)
    return path


def load(directory, skipped: list | None = None) -> list[dict]:
    """Every run recorded in ``directory``, oldest first. JSON files of another kind
    are passed over; a history record that cannot be read or is malformed is skipped
    and, when ``skipped`` is given, added to it as ``(path, why)``."""
    runs = []
    d = Path(directory)
    if not d.is_dir():
        raise _report.ReportError(f"history directory {str(d)!r} does not exist (write one with "
                                  f"--flockai-history DIR)")
    for p in sorted(d.glob("*.json")):
        try:
            doc = _report.read_json(p, "history record")
        except _report.ReportError as exc:
            if skipped is not None:
                skipped.append((p, str(exc)))
            continue
        if not isinstance(doc, dict) or doc.get("schema") != SCHEMA:
            continue
        why = malformed(doc)
        if why is None:
            runs.append(doc)
        elif skipped is not None:
            skipped.append((p, why))
    runs.sort(key=lambda r: str(r.get("created")))
    return runs


def malformed(doc: dict) -> str | None:
    """Why a history record cannot be used, or None."""
    for field in ("commit", "branch", "created"):
        if doc.get(field) is not None and not isinstance(doc.get(field), str):
            return f"{field} = {doc.get(field)!r} is not a string"
    tests = doc.get("tests")
    if not isinstance(tests, dict):
        return f"'tests' must map test ids to flights, not {type(tests).__name__}"
    for nodeid, flights in tests.items():
        if not isinstance(flights, dict) or not all(isinstance(k, dict)
                                                    for k in flights.values()):
            return f"test {nodeid!r} must map flight names to {{kpi: number}}"
        for kp in flights.values():
            for kpi, v in kp.items():
                if v is not None and (isinstance(v, bool) or not isinstance(v, (int, float))):
                    return f"test {nodeid!r} KPI {kpi!r} = {v!r} is not a number"
    return None


def series(runs: list[dict], kpi: str, test: str | None = None) -> dict:
    """``{"<test> / <flight>": [value or None per run]}`` for the runs given."""
    names: list = []
    for r in runs:
        for nodeid, flights in r["tests"].items():
            if test is not None and test not in nodeid:
                continue
            for flight, kp in flights.items():
                if kpi in kp and (nodeid, flight) not in names:
                    names.append((nodeid, flight))
    out = {}
    for nodeid, flight in names:
        out[f"{nodeid} / {flight}"] = [
            r["tests"].get(nodeid, {}).get(flight, {}).get(kpi) for r in runs]
    return out


def render(runs: list[dict], kpi: str, test: str | None = None) -> str:
    """One row per run (date, commit), one column per flight with the KPI."""
    s = series(runs, kpi, test)
    if not s:
        return f"no run in the history has the KPI {kpi!r}"
    headers = ["run", "commit"] + [f"[{i + 1}]" for i in range(len(s))]
    rows = []
    for j, r in enumerate(runs):
        commit = (r.get("commit") or "-")[:10] + ("+" if r.get("dirty") else "")
        rows.append([str(r.get("created", ""))[:19], commit]
                    + [_report.format_kpi(kpi, v[j]) for v in s.values()])
    legend = [f"[{i + 1}] {name}" for i, name in enumerate(s)]
    return "\n".join([f"{kpi} over {len(runs)} run(s)", _report.table(headers, rows, indent="")]
                     + legend)


def run_label(run: dict) -> str:
    """A run on the x axis: its tag, else its short commit (``+`` when dirty), else its date."""
    if run.get("tag"):
        return str(run["tag"])
    if run.get("commit"):
        return str(run["commit"])[:7] + ("+" if run.get("dirty") else "")
    return str(run.get("created", "?"))[5:16].replace("T", " ")


def series_label(name: str, width: int = 48) -> str:
    """``tests/test_x.py::test_hover[a] / flight`` -> ``test_hover[a] / flight``, cut in
    the middle (never from the left) when longer than ``width``."""
    nodeid, _, flight = name.rpartition(" / ")
    short = f"{nodeid.split('::', 1)[-1]} / {flight}" if nodeid else name
    if len(short) <= width:
        return short
    keep = (width - 1) // 2
    return short[:keep] + "…" + short[-(width - 1 - keep):]


_LINESTYLES = ("-", "--", ":", "-.")
_MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*", "<", ">")


def style(i: int) -> dict:
    """The i-th series' style: 10 colours, then a new line style and marker each 10."""
    return {"color": f"C{i % 10}", "linestyle": _LINESTYLES[(i // 10) % len(_LINESTYLES)],
            "marker": _MARKERS[(i + i // 10) % len(_MARKERS)]}


def trend_fig(runs: list[dict], kpi: str, test: str | None = None):
    """The trend of ``kpi`` across ``runs`` as a matplotlib Figure (needs matplotlib):
    one line per test and flight, the runs labelled by tag or short commit."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise _report.ReportError("drawing the history needs matplotlib: pip install "
                                  "'pytest-flockai[plots]'") from None
    s = series(runs, kpi, test)
    rows = (len(s) + 1) // 2
    fig, ax = plt.subplots(figsize=(9, 4 + 0.22 * rows))
    for i, (name, values) in enumerate(s.items()):
        xs = [j for j, v in enumerate(values) if v is not None]
        ax.plot(xs, [values[j] for j in xs], label=series_label(name), ms=5, **style(i))
    ax.set_xticks(range(len(runs)), [run_label(r) for r in runs], rotation=45, ha="right")
    info = _kpis.get(kpi)
    ax.set_ylabel(f"{kpi} ({info.unit})" if info is not None and info.unit not in ("1", "count")
                  else kpi)
    ax.set_title(f"{kpi} by commit")
    ax.grid(alpha=0.3)
    if s:
        ax.legend(fontsize=7, ncol=2, loc="upper center", bbox_to_anchor=(0.5, -0.22),
                  frameon=False)
    fig.tight_layout()
    return fig


def plot(runs: list[dict], kpi: str, path, test: str | None = None) -> Path:
    """Draw the trend of ``kpi`` into ``path`` (PNG, ``trend_fig``); needs matplotlib."""
    fig = trend_fig(runs, kpi, test)
    p = Path(path)
    try:
        atomic_write(p, lambda fh: fig.savefig(fh, dpi=100, format="png", bbox_inches="tight"),
                     text=False)
    finally:
        import matplotlib.pyplot as plt
        plt.close(fig)
    return p
