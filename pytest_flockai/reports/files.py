"""The report files: the JSON report, baselines, artifacts and the text tables.

The JSON report (schema ``"pytest-flockai/1"``) and the baseline
(``"pytest-flockai-baseline/1"``) are described field by field in
docs/reference/json-report.md. Reports are written atomically, at the end of the
session, also when tests fail or the session is interrupted. This module is used by
the plugin only (it needs no pytest itself).
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import json
import math
import os
import platform
import re
import stat
import sys
import tempfile
import warnings
from importlib import metadata
from pathlib import Path

from .. import kpis as _kpis
from .. import limits
from .._io import atomic_write, json_depth, printable, replace_from
from ..errors import ConfigError

SCHEMA = "pytest-flockai/1"
BASELINE_SCHEMA = "pytest-flockai-baseline/1"

_PACKAGES = ("pytest-flockai", "pytest", "pytest-xdist", "mujoco", "numpy", "pandas",
             "hypothesis", "onnxruntime", "opencv-python-headless")


class ReportError(ConfigError):
    """A report or baseline file cannot be read or written (the plugin makes it a UsageError).
    A ``ConfigError``: a bad report path or baseline file is bad input."""


# -- JSON-ready values ----------------------------------------------------------
def jsonable(obj):
    """A copy of ``obj`` made of dict/list/str/int/float/bool/None only.

    numpy scalars and arrays become Python numbers and lists, tuples become
    lists, non-finite floats become None, anything else its ``str``.
    """
    if obj is None or isinstance(obj, (bool, str)):
        return obj
    if isinstance(obj, int):
        return int(obj)
    if isinstance(obj, float):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple, set, frozenset)):
        return [jsonable(v) for v in obj]
    tolist = getattr(obj, "tolist", None)     # numpy scalars and arrays
    if callable(tolist):
        try:
            return jsonable(tolist())
        except Exception:  # pragma: no cover - exotic objects
            pass
    if isinstance(obj, os.PathLike):
        return os.fspath(obj)
    return str(obj)


def environment() -> dict:
    """Python, platform and package versions of this run (None: not installed)."""
    pk: dict[str, str | None] = {}
    for name in _PACKAGES:
        try:
            pk[name] = metadata.version(name)
        except metadata.PackageNotFoundError:
            pk[name] = None
    return {"python": platform.python_version(), "implementation": platform.python_implementation(),
            "platform": platform.platform(), "machine": platform.machine(),
            "executable": sys.executable, "packages": pk}


# -- files ------------------------------------------------------------------------
def check_writable(path: Path, what: str) -> None:
    """Raise ReportError unless ``path`` can be written (its directory exists and
    accepts a new file; the path is not a directory)."""
    path = Path(path)
    if str(path) in ("", "."):
        raise ReportError(f"{what} {str(path)!r} is not allowed; expected a file path")
    if path.is_dir():
        raise ReportError(f"{what} {str(path)!r} is a directory; give a file path")
    if path.exists() and not path.is_file():
        raise ReportError(f"{what} {str(path)!r} is a special file (a device, a FIFO or a "
                          f"socket); it would be replaced: give the path of a regular file")
    parent = path.parent
    if not parent.is_dir():
        raise ReportError(f"{what} {str(path)!r}: directory {str(parent)!r} does not exist")
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".check", dir=parent)
        os.close(fd)
        os.unlink(tmp)
    except OSError as exc:
        raise ReportError(f"{what} {str(path)!r} is not writable: {exc.strerror or exc}") from None
    if path.exists() and not os.access(path, os.W_OK):
        raise ReportError(f"{what} {str(path)!r} exists and is not writable")


def read_json(path, what: str):
    """The JSON document in ``path``; ReportError naming ``what`` and the file when it
    is missing, a folder, not a regular file (a FIFO is never opened: it would block),
    unreadable, not JSON, or nested deeper than ``limits.MAX_JSON_DEPTH``."""
    path = Path(path)
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise ReportError(f"{what} {str(path)!r} does not exist") from None
    except OSError as exc:
        raise ReportError(f"{what} {str(path)!r} cannot be read: {exc.strerror or exc}") from None
    if stat.S_ISDIR(st.st_mode):
        raise ReportError(f"{what} {str(path)!r} is a folder; expected a JSON file")
    if not stat.S_ISREG(st.st_mode):
        raise ReportError(f"{what} {str(path)!r} is not a regular file (a device, a FIFO or "
                          f"a socket); expected a JSON file")
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ReportError(f"{what} {str(path)!r} cannot be read: {exc}") from None
    try:
        data = json.loads(text)
    except RecursionError:
        data = _TOO_DEEP
    except ValueError as exc:
        raise ReportError(f"{what} {str(path)!r} is not valid JSON: {exc}") from None
    limit = limits.MAX_JSON_DEPTH
    if data is _TOO_DEEP or json_depth(data, limit) > limit:
        raise ReportError(f"{what} {str(path)!r} is nested deeper than "
                          f"pytest_flockai.limits.MAX_JSON_DEPTH = {limits.MAX_JSON_DEPTH}")
    return data


_TOO_DEEP = object()


def write_json_atomic(path: Path, data) -> None:
    """Write ``data`` as JSON to ``path`` through a temporary file and ``os.replace``."""
    path = Path(path)
    text = json.dumps(jsonable(data), indent=2, sort_keys=False, allow_nan=False) + "\n"
    atomic_write(path, lambda fh: fh.write(text))


# -- the JSON report -------------------------------------------------------------------
def build_report(tests: list[dict], *, exitstatus=0, interrupted=False, options=None) -> dict:
    """The ``pytest-flockai/1`` document from per-test entries (see the module doc)."""
    summary: dict = {"tests": len(tests)}
    for t in tests:
        summary[t["outcome"]] = summary.get(t["outcome"], 0) + 1
    summary["flights"] = sum(len(t.get("flights", ())) for t in tests)
    return {
        "schema": SCHEMA,
        "created": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
        "interrupted": bool(interrupted),
        "exitstatus": int(exitstatus) if exitstatus is not None else None,
        "environment": environment(),
        "options": options or {},
        "summary": summary,
        "tests": tests,
    }


# -- baselines ---------------------------------------------------------------------------
def baseline_from_tests(tests: list[dict]) -> dict:
    """``{"schema": ..., "tests": {nodeid: {flight: kpis}}}`` for the tests that flew
    (the plugin adds ``scenarios``, ``reports.scenario.of_report``)."""
    out = {}
    for t in tests:
        flights = {f["name"]: dict(f["kpis"]) for f in t.get("flights", ())}
        if flights:
            out[t["nodeid"]] = flights
    return {"schema": BASELINE_SCHEMA, "tests": out}


def load_baseline(path: Path) -> dict:
    """``{nodeid: {flight: {kpi: value}}}`` from a baseline or a JSON report.

    Raises ReportError for a missing, unreadable or malformed file."""
    path = Path(path)
    if not path.exists() and not path.is_symlink():
        raise ReportError(f"baseline file {str(path)!r} does not exist (write one with "
                          f"--flockai-save PATH)")
    data = read_json(path, "baseline file")
    if isinstance(data, dict) and data.get("schema") == SCHEMA:       # a JSON report
        tests = check_entries(data.get("tests"), path, "baseline file", outcome=False)
        data = {_nodeid(t): {f["name"]: f["kpis"] for f in t.get("flights", ())}
                for t in tests}
    elif isinstance(data, dict) and "schema" in data:
        if data["schema"] != BASELINE_SCHEMA:
            raise ReportError(f"baseline file {str(path)!r}: schema {data['schema']!r} is not "
                              f"supported; allowed: {BASELINE_SCHEMA!r}, {SCHEMA!r}")
        data = data.get("tests")
    if not isinstance(data, dict):
        raise ReportError(f"baseline file {str(path)!r}: expected {{nodeid: {{flight: {{kpi: "
                          f"value}}}}}}, got {type(data).__name__}")
    for nodeid, flights in data.items():
        if not isinstance(flights, dict) or not all(isinstance(k, dict) for k in flights.values()):
            raise ReportError(f"baseline file {str(path)!r}: entry {nodeid!r} must map flight "
                              f"names to {{kpi: number}}")
        for fname, kp in flights.items():
            for kpi, v in kp.items():
                if v is None:       # a KPI that was not finite when saved: not compared
                    continue
                if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                    raise ReportError(
                        f"baseline file {str(path)!r}: {nodeid} flight {fname!r} KPI {kpi!r} "
                        f"= {v!r} is not allowed; expected a finite number (or null for a KPI "
                        f"that is not compared)")
    return data


def check_entries(tests, path, what: str = "report", *, outcome: bool = True) -> list:
    """The test entries of a ``pytest-flockai/1`` report, each checked (a dict with a
    string ``nodeid`` and, with ``outcome``, a string ``outcome``; ``flights`` a list of {"name": str, "kpis": dict});
    one ReportError line naming the file, the entry and what is wrong otherwise."""
    where = f"{what} {str(path)!r}: malformed report"
    if not isinstance(tests, list):
        raise ReportError(f"{where}: 'tests' = {_short(tests)} is not allowed; expected a "
                          f"list of test entries, each with a string 'nodeid'")
    for i, t in enumerate(tests):
        if not isinstance(t, dict) or not isinstance(t.get("nodeid"), str):
            raise ReportError(f"{where}: tests[{i}] = {_short(t)} is not allowed; expected a "
                              f"test entry with a string 'nodeid'")
        at = f"{where}: tests[{i}] ({t['nodeid']!r})"
        if (outcome or "outcome" in t) and not isinstance(t.get("outcome"), str):
            raise ReportError(f"{at}: outcome = {_short(t.get('outcome'))} is not allowed; "
                              f"expected a string such as 'passed'")
        flights = t.get("flights", [])
        if not isinstance(flights, list):
            raise ReportError(f"{at}: flights = {_short(flights)} is not allowed; expected a "
                              f"list of flights")
        for j, f in enumerate(flights):
            if not isinstance(f, dict) or not isinstance(f.get("name"), str) \
                    or not isinstance(f.get("kpis"), dict):
                raise ReportError(f"{at}: flights[{j}] = {_short(f)} is not allowed; expected "
                                  f"{{'name': str, 'kpis': {{kpi: number}}, ...}}")
    return tests


def _short(v) -> str:
    r = repr(v)
    return r if len(r) <= 60 else r[:57] + "..."


def _nodeid(test) -> str:
    """A report entry's node id; TypeError unless the entry is a dict with a str id."""
    nodeid = test.get("nodeid") if isinstance(test, dict) else None
    if not isinstance(nodeid, str):
        raise TypeError(f"a test entry without a string 'nodeid': {str(test)[:60]}")
    return nodeid


def regressions(flights: dict, base: dict, max_regression_pct: float, *,
                per_kpi: dict | None = None, abs_tol: dict | None = None) -> list[dict]:
    """KPIs of ``flights`` ({flight: kpis}) worse than ``base`` ({flight: kpis}) by
    more than ``max_regression_pct`` percent (or ``per_kpi[kpi]`` percent) and
    more than the KPI's absolute tolerance (``kpis.abs_tolerance``, or
    ``abs_tol[kpi]`` by name or family): ``kpis.classify``'s "regression", the
    rule ``flockai compare`` applies too.

    KPIs without a better direction, missing on either side or non-finite are
    not compared."""
    out = []
    per_kpi = per_kpi or {}
    for fname, kp in flights.items():
        bk = base.get(fname)
        if not bk:
            continue
        for kpi, b in bk.items():
            a = kp.get(kpi)
            if a is None or b is None:
                continue
            a, b = float(a), float(b)
            better, status = _kpis.classify(kpi, b, a, per_kpi.get(kpi, max_regression_pct),
                                            abs_tol)
            if status == "regression":
                change = (a - b) / abs(b) * 100.0 if b != 0 else math.inf
                out.append({"flight": fname, "kpi": kpi, "baseline": b, "actual": a,
                            "change_pct": change, "better": better})
    return out


# -- artifacts -----------------------------------------------------------------------------
def safe_name(name: str) -> str:
    """A file name for a test id or flight name: the name itself when it is
    already a plain file name, else a readable version of it with a short hash
    of the full name (``a/b``, ``a_b``, ``a:b`` and ``a b`` get different
    folders; long ids stay unique; nothing becomes hidden, ``..`` or empty)."""
    clean = re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip("_.")
    if clean and clean == name and len(clean) <= 150:
        return clean
    digest = hashlib.sha256(name.encode("utf-8", "surrogatepass")).hexdigest()[:10]
    return f"{clean[:120] or 'test'}-{digest}"


def write_artifacts(directory: Path, nodeid: str, flight: str, result) -> Path:
    """Telemetry CSV and the flight's JSON (scenario, KPIs, events), and per detection task
    its COCO truth and results files, under ``directory/<nodeid>/``; returns that folder."""
    folder = Path(directory) / safe_name(nodeid)
    folder.mkdir(parents=True, exist_ok=True)
    name = safe_name(flight)
    atomic_write(folder / f"{name}.telemetry.csv", lambda fh: result.telemetry.to_csv(fh))
    write_json_atomic(folder / f"{name}.json", result.to_dict())
    for task, (truth, predictions) in (getattr(result, "ml_coco", None) or {}).items():
        # a detection task's frames as COCO files (pycocotools, FiftyOne): truth and results
        write_json_atomic(folder / f"{name}.{safe_name(task)}.truth.json", truth)
        write_json_atomic(folder / f"{name}.{safe_name(task)}.results.json", predictions)
    from .. import plots  # lazy: numpy, and matplotlib (see tests/project/test_architecture.py)
    if plots.available():
        _picture(plots.energy_figure, result, folder / f"{name}.energy.png")
        _picture(plots.path_figure, result, folder / f"{name}.path.png")
    else:
        warnings.warn("pytest-flockai: matplotlib is not installed, so --flockai-artifacts writes "
                      "telemetry and JSON but no pictures (pip install 'pytest-flockai[plots]')",
                      stacklevel=2)
    return folder


def _picture(draw, result, path: Path) -> None:
    """``draw(result, tmp)`` into a temporary PNG beside ``path``, then renamed over it
    (a full disk leaves the old picture or none, never a cut-off one)."""
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp.png")
    os.close(fd)
    try:
        draw(result, Path(tmp))
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    replace_from(tmp, path)


# -- text ------------------------------------------------------------------------------------------
_FRACTIONS = ("energy_share_", "battery_remaining", "cpu_utilization", "mem_utilization",
              "detection_precision", "detection_recall")


def format_kpi(name: str, value) -> str:
    """A KPI value for humans: SI number with its unit; fractions as percent."""
    if value is None:
        return "n/a"
    v = float(value)
    if math.isnan(v):
        return "nan"
    info = _kpis.get(name)
    unit = info.unit if info is not None else ""
    if unit == "fraction":
        return f"{v * 100:.3g}%"
    if unit in ("1", "count"):
        if name.startswith(_FRACTIONS):
            return f"{v * 100:.3g}%"
        return f"{v:.6g}"
    return f"{v:.4g} {unit}".rstrip()


def table(headers: list[str], rows: list[list[str]], indent: str = "  ") -> str:
    """A plain left-aligned text table."""
    widths = [len(h) for h in headers]
    for r in rows:
        for i, c in enumerate(r):
            widths[i] = max(widths[i], len(c))
    lines = [indent + "  ".join(h.ljust(w) for h, w in zip(headers, widths)).rstrip(),
             indent + "  ".join("-" * w for w in widths)]
    lines += [indent + "  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in rows]
    return "\n".join(lines)


__all__ = ["BASELINE_SCHEMA", "SCHEMA", "ReportError", "baseline_from_tests", "build_report",
           "check_entries", "check_writable", "environment", "format_kpi", "jsonable", "load_baseline",
           "printable", "read_json", "regressions", "safe_name", "table", "write_artifacts",
           "write_json_atomic"]
