"""Compare the KPIs of a ``--flockai-json`` report with a golden file recorded
before a change: ``python tests/golden/compare.py GOLDEN.json REPORT.json``.
Prints every flight whose KPIs or end reason differ; exit 1 if any do. A
flight found under another name with identical KPIs counts as renamed (the
one naming rule of a test's flights renames, it does not change KPIs), not as a difference; new flights are listed apart."""

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
    diffs = renamed = new = 0
    for test in sorted(set(g) | set(r)):
        for name in sorted(set(g.get(test, {})) | set(r.get(test, {}))):
            a, b = g.get(test, {}).get(name), r.get(test, {}).get(name)
            if b is None:
                twin = [n for n, f in r.get(test, {}).items()
                        if f["kpis"].keys() == a["kpis"].keys()
                        and all(same(a["kpis"][k], f["kpis"][k]) for k in a["kpis"])]
                if twin:
                    renamed += 1
                    continue
                print(f"{test} [{name}]: only in golden")
                diffs += 1
                continue
            if a is None:
                new += 1
                continue
            keys = set(a["kpis"]) | set(b["kpis"])
            bad = [k for k in sorted(keys) if not same(a["kpis"].get(k), b["kpis"].get(k))]
            if bad or a["end_reason"] != b["end_reason"]:
                diffs += 1
                print(f"{test} [{name}]: " + ", ".join(
                    f"{k} {a['kpis'].get(k)} -> {b['kpis'].get(k)}" for k in bad[:6]))
    n = sum(len(v) for v in g.values())
    print(f"{n} golden flights: {diffs} differ, {renamed} renamed with identical KPIs; "
          f"{new} flights new in the report")
    return 1 if diffs else 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:3]))
