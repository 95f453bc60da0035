"""The ``flockai`` command.

``flockai merge OUT.json IN1.json IN2.json ...`` merges JSON reports written by
``--flockai-json`` on several machines or CI shards (e.g. ``pytest
--splits``/``-k`` per job, or xdist ``--tx`` across hosts) into one report
with the same schema; a test present in several inputs keeps its last entry.
``flockai blueprints`` lists the built-in drones. ``flockai compare`` and
``flockai history`` compare runs across commits (``reports/commands.py``).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from . import report as _report
from .airframe import blueprints
from .reports import commands as _commands


def merge_reports(paths) -> dict:
    """One ``pytest-flockai/1`` report from several; raises ReportError on a bad input."""
    docs = []
    for p in paths:
        try:
            with open(p) as fh:
                doc = json.load(fh)
        except (OSError, ValueError) as exc:
            raise _report.ReportError(f"cannot read report {str(p)!r}: {exc}") from None
        if not isinstance(doc, dict) or doc.get("schema") != _report.SCHEMA:
            raise _report.ReportError(f"{str(p)!r} is not a {_report.SCHEMA} report "
                                      f"(schema = {doc.get('schema') if isinstance(doc, dict) else None!r})")
        docs.append(doc)
    tests: dict[str, dict] = {}
    for doc in docs:
        for t in doc.get("tests", []):
            tests[t["nodeid"]] = t
    exit_codes = [d.get("exitstatus") for d in docs if d.get("exitstatus") is not None]
    merged = _report.build_report(list(tests.values()),
                                  exitstatus=max(exit_codes) if exit_codes else 0,
                                  interrupted=any(d.get("interrupted") for d in docs),
                                  options=docs[0].get("options", {}) if docs else {})
    merged["merged_from"] = [str(p) for p in paths]
    merged["environments"] = [d.get("environment") for d in docs]
    return merged


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="flockai", description="pytest-flockai tools")
    sub = ap.add_subparsers(dest="cmd", required=True)
    m = sub.add_parser("merge", help="merge --flockai-json reports from several machines or shards")
    m.add_argument("out", type=Path)
    m.add_argument("inputs", type=Path, nargs="+")
    sub.add_parser("blueprints", help="list the built-in drone blueprints")
    _commands.add_parsers(sub)
    a = ap.parse_args(argv)
    rc = _commands.run(a)
    if rc is not None:
        return rc
    if a.cmd == "blueprints":
        print("\n".join(blueprints()))
        return 0
    try:
        merged = merge_reports(a.inputs)
        _report.write_json_atomic(a.out, merged)
    except _report.ReportError as exc:
        print(f"flockai merge: {exc}", file=sys.stderr)
        return 2
    s = merged["summary"]
    print(f"flockai merge: {s['tests']} test(s), {s['flights']} flight(s) from {len(a.inputs)} "
          f"report(s) -> {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
