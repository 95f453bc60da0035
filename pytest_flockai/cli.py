"""The ``flockai`` command.

``flockai merge OUT.json IN1.json IN2.json ...`` merges JSON reports written by
``--flockai-json`` on several machines or CI shards (e.g. ``pytest
--splits``/``-k`` per job, or xdist ``--tx`` across hosts) into one report
with the same schema; a test present in several inputs keeps its last entry.
``flockai blueprints`` lists the built-in drones. ``flockai compare`` and
``flockai history`` compare runs across commits (``reports/subcommands.py``);
``flockai cache info|clear|prune`` shows, empties and trims the flight cache (only
files carrying the cache's own header are ever removed). ``flockai profile-device``
times ONNX models on this computer (``compute/profiler.py``); ``flockai predict-latency``
predicts a model's latency on the computer profiles (``compute/latency_cli.py``).

Exit statuses, the same for every subcommand (docs/how-to/ci-cache.md):
0 done, 1 a regression (``compare`` only), 2 a usage or input error (a bad
argument, a file that is missing, malformed or cannot be written: one line on
stderr naming it), 3 an internal error (a bug: one line, never a traceback).
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from . import cache as _cache
from . import limits
from .airframe import blueprints
from .compute import latency_cli as _latency_cli
from .compute import profiler as _profiler
from .errors import ConfigError, FlockAIError
from .reports import files as _report
from .reports import subcommands as _commands

__all__ = ["main"]

OK, REGRESSION, USAGE, INTERNAL = 0, 1, 2, 3
#: where pytest keeps the flight cache, from the project's root (``harness/flightcache.py``)
DEFAULT_CACHE = Path(".pytest_cache") / "d" / "flockai-flights"
_UNITS = {"": 1, "b": 1, "k": 2**10, "kb": 2**10, "m": 2**20, "mb": 2**20, "g": 2**30,
          "gb": 2**30, "t": 2**40, "tb": 2**40}


def merge_reports(paths) -> dict:
    """One ``pytest-flockai/1`` report from several; raises ReportError on a bad input."""
    docs = []
    for p in paths:
        doc = _report.read_json(p, "report")
        if not isinstance(doc, dict) or doc.get("schema") != _report.SCHEMA:
            raise _report.ReportError(f"{str(p)!r} is not a {_report.SCHEMA} report "
                                      f"(schema = {doc.get('schema') if isinstance(doc, dict) else None!r})")
        _report.check_entries(doc.get("tests", []), p, "report")
        docs.append(doc)
    tests: dict[str, dict] = {}
    for doc in docs:
        for t in doc.get("tests", []):
            tests[t["nodeid"]] = t
    exit_codes = [int(d["exitstatus"]) for d in docs if isinstance(d.get("exitstatus"), int)]
    merged = _report.build_report(list(tests.values()),
                                  exitstatus=max(exit_codes) if exit_codes else 0,
                                  interrupted=any(d.get("interrupted") for d in docs),
                                  options=docs[0].get("options", {}) if docs else {})
    merged["merged_from"] = [str(p) for p in paths]
    merged["environments"] = [d.get("environment") for d in docs]
    return merged


def _parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="flockai", description="pytest-flockai tools",
                                 epilog="exit status: 0 done, 1 a regression (compare), 2 a "
                                        "usage or input error, 3 an internal error")
    sub = ap.add_subparsers(dest="cmd", required=True)
    m = sub.add_parser("merge", help="merge --flockai-json reports from several machines or shards")
    m.add_argument("out", type=Path)
    m.add_argument("inputs", type=Path, nargs="+")
    sub.add_parser("blueprints", help="list the built-in drone blueprints")
    _commands.add_parsers(sub)
    _profiler.add_parser(sub)
    _latency_cli.add_parser(sub)
    c = sub.add_parser("cache", help="the flight cache: info, clear or prune it")
    csub = c.add_subparsers(dest="cache_cmd", required=True)
    for name, help_ in (("info", "entries, size, limit and key source of the flight cache"),
                        ("clear", "remove every entry (files with the cache's header only)"),
                        ("prune", "remove the least recently used entries")):
        sp = csub.add_parser(name, help=help_)
        sp.add_argument("directory", type=Path, nargs="?", default=DEFAULT_CACHE,
                        help=f"the cache folder (default: {DEFAULT_CACHE})")
    sp.add_argument("--max-size", default=None, help="keep at most this much, e.g. 500M, 2G "
                    "(default: pytest_flockai.limits.MAX_CACHE_BYTES)")
    sp.add_argument("--older-than", type=float, default=None, metavar="DAYS",
                    help="also remove entries unused for DAYS days")
    sp.add_argument("--all", action="store_true", help="remove every entry")
    return ap


def parse_size(text) -> int:
    """``"500M"``, ``"2G"``, ``"1048576"`` -> bytes; ConfigError for anything else."""
    raw = str(text).strip().lower()
    num = raw.rstrip("kmgtb")
    unit = raw[len(num):]
    try:
        value = float(num) * _UNITS[unit]
    except (ValueError, KeyError):
        value = -1.0
    if not 0 <= value < 2**63:
        raise ConfigError(f"--max-size = {text!r} is not allowed; expected a size >= 0 such "
                          f"as 500M or 2G")
    return int(value)


def _cache_cmd(a) -> int:
    d = a.directory
    if not d.is_dir():
        raise ConfigError(f"cache folder {str(d)!r} does not exist (pytest makes it under "
                          f"its cache_dir: {DEFAULT_CACHE})")
    cache = _cache.FlightCache(d, "off")
    if a.cache_cmd == "info":
        i = cache.info()
        print(_report.printable(
            f"flight cache {i['directory']}: {i['flights']} flight(s), {i['memo']} memoised "
            f"value(s), {i['bytes'] / 2**20:.1f} MiB of {i['limit_bytes'] / 2**20:.0f} MiB "
            f"(limits.MAX_CACHE_BYTES); key from {i['key_source']}"))
        return OK
    if a.cache_cmd == "clear":
        removed = cache.clear()
        print(_report.printable(f"flockai cache clear: removed {removed} entr"
                                f"{'y' if removed == 1 else 'ies'} from {d}"))
        return OK
    if a.older_than is not None and not a.older_than >= 0:
        raise ConfigError(f"--older-than = {a.older_than!r} is not allowed; expected days >= 0")
    keep = 0 if a.all else (limits.MAX_CACHE_BYTES if a.max_size is None
                            else parse_size(a.max_size))
    older = None if a.older_than is None else a.older_than * 86400.0
    removed, freed = cache.prune(keep, older)
    print(_report.printable(f"flockai cache prune: removed {removed} entr"
                            f"{'y' if removed == 1 else 'ies'} ({freed / 2**20:.1f} MiB) "
                            f"from {d}"))
    return OK


def main(argv=None) -> int:
    a = _parser().parse_args(argv)          # a usage error exits 2 (argparse)
    try:
        status = _run(a)
        sys.stdout.flush()                   # a reader that left shows here, not at exit
        return status
    except BrokenPipeError:                 # `flockai blueprints | head`: not an error
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return OK
    except (FlockAIError, OSError, RecursionError, MemoryError) as exc:
        _say(a.cmd, str(exc) if isinstance(exc, FlockAIError) else
             f"{type(exc).__name__}: {exc}")
        return USAGE
    except Exception as exc:  # noqa: BLE001 (a bug: one line, never a traceback)
        _say(a.cmd, f"internal error ({type(exc).__name__}: {exc}); please report it")
        return INTERNAL


def _say(cmd: str, text: str) -> None:
    print(_report.printable(f"flockai {cmd}: {text}"), file=sys.stderr)


def _run(a) -> int:
    rc = _commands.run(a)
    if rc is not None:
        return rc
    if a.cmd == "blueprints":
        print("\n".join(blueprints()))
        return OK
    if a.cmd == "cache":
        return _cache_cmd(a)
    if a.cmd == "profile-device":
        return _profiler.run_cli(a)
    if a.cmd == "predict-latency":
        return _latency_cli.run_cli(a)
    _report.check_writable(a.out, "flockai merge: OUT")
    merged = merge_reports(a.inputs)
    _report.write_json_atomic(a.out, merged)
    s = merged["summary"]
    print(_report.printable(f"flockai merge: {s['tests']} test(s), {s['flights']} flight(s) "
                            f"from {len(a.inputs)} report(s) -> {a.out}"))
    return OK


if __name__ == "__main__":
    sys.exit(main())
