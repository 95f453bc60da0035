"""Compare the KPIs of a ``--flockai-json`` report with a golden file recorded
before a change: ``python tests/golden/compare.py GOLDEN.json REPORT.json``.
Prints every flight whose KPIs or end reason differ; exit 1 if any do."""

import json
import math
import sys


def flights(path):
    d = json.load(open(path))
    if "tests" not in d:
        return d
    out = {}
    for t in d["tests"]:
        for f in t.get("flights", []):
            out.setdefault(t["nodeid"], {})[f["name"]] = {"end_reason": f.get("end_reason"),
                                                          "kpis": f["kpis"]}
    return out


def same(a, b):
    if isinstance(a, float) or isinstance(b, float):
        a, b = float(a), float(b)
        return a == b or (math.isnan(a) and math.isnan(b))
    return a == b


def main(golden, report):
    g, r = flights(golden), flights(report)
    diffs = 0
    for test in sorted(set(g) | set(r)):
        for name in sorted(set(g.get(test, {})) | set(r.get(test, {}))):
            a, b = g.get(test, {}).get(name), r.get(test, {}).get(name)
            if a is None or b is None:
                print(f"{test} [{name}]: only in {'report' if a is None else 'golden'}")
                diffs += 1
                continue
            keys = set(a["kpis"]) | set(b["kpis"])
            bad = [k for k in sorted(keys) if not same(a["kpis"].get(k), b["kpis"].get(k))]
            if bad or a["end_reason"] != b["end_reason"]:
                diffs += 1
                print(f"{test} [{name}]: " + ", ".join(
                    f"{k} {a['kpis'].get(k)} -> {b['kpis'].get(k)}" for k in bad[:6]))
    n = sum(len(v) for v in r.values())
    print(f"{n} flights compared, {diffs} differ")
    return 1 if diffs else 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:3]))
