"""Latency model against published batch-1 measurements (issue 34), per half.

For each half (``tuning``: the efficiencies were chosen on it; ``heldout``: never seen by
the fit), per computer, per runtime and per computer/runtime: the number of rows, the
median and the worst ratio predicted/published, and how many rows are within 2x. The
target on the held-out half: for each computer with at least 8 rows, median
|ln(predicted/published)| <= ln 1.25 and no row beyond 2x.

    python benchmarks/latency_validation.py [--rows] [--markdown FILE]
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from pytest_flockai._io import atomic_write
from pytest_flockai.compute import predict, published

MIN_ROWS, MEDIAN_BOUND = 8, math.log(1.25)


def table_lines(s: dict) -> list[str]:
    out = ["| half | by | name | rows | median ratio | median abs ln | worst ratio | within 2x | "
           "target met |", "|---|---|---|---|---|---|---|---|---|"]
    for half, v in s.items():
        for by in ("computer", "runtime", "computer/runtime"):
            for name, st in v[by].items():
                met = ""
                if by == "computer" and st["n"] >= MIN_ROWS:
                    ok = st["median_abs_ln"] <= MEDIAN_BOUND and st["within_2x"] == st["n"]
                    met = "yes" if ok else "no"
                out.append(f"| {half} | {by} | {name} | {st['n']} | {st['median_ratio']:.2f} | "
                           f"{st['median_abs_ln']:.3f} | {st['worst_ratio']:.2f} | "
                           f"{st['within_2x']}/{st['n']} | {met} |")
        al = v["all"]
        out.append(f"| {half} | all | all | {al['n']} | {al['median_ratio']:.2f} | "
                   f"{al['median_abs_ln']:.3f} | {al['worst_ratio']:.2f} | "
                   f"{al['within_2x']}/{al['n']} | |")
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", action="store_true", help="print every row's ratio")
    ap.add_argument("--markdown", help="also write the table as Markdown to this file")
    ap.add_argument("--networks", default=str(published.NETWORKS),
                    help="folder of the per-node network summaries")
    a = ap.parse_args(argv)
    rows, skipped = published.load_rows(networks=Path(a.networks))
    table = predict.efficiencies()
    if not rows:
        print("no usable rows:", *skipped[:10], sep="\n  ")
        return 1
    if not table:
        print("no tuned efficiencies yet (run benchmarks/latency_tune.py): untuned priors")
    s = published.summary(rows, table)
    lines = table_lines(s)
    print("\n".join(lines))
    if a.rows:
        for r, q in zip(rows, published.ratios(rows, table)):
            print(f"{r.half:8s} {r.row_id:>6s} {r.computer:24s} {r.group:26s} "
                  f"{r.network}-{r.input:5s} published {1e3 * r.latency_s:9.2f} ms  "
                  f"predicted/published {q:6.2f}")
    print("\nEnergy per inference against the published watt-meter figures "
          "(predicted latency x busy power, whole board):")
    for e in published.energy_check(table, networks=Path(a.networks)):
        if "skipped" in e:
            print(f"  {e['id']}: skipped ({e['skipped']})")
        else:
            print(f"  {e['id']}: {e['computer']} {e['deployment']} {e['network']}: published "
                  f"{e['published_j']:.3f} J, predicted {e['predicted_j']:.3f} J, ratio "
                  f"{e['ratio']:.2f}")
    print(f"{len(rows)} rows used, {len(skipped)} skipped")
    for why in skipped:
        print("  skipped", why)
    if a.markdown:
        text = "\n".join(lines) + "\n"
        atomic_write(Path(a.markdown), lambda fh: fh.write(text))
    return 0


if __name__ == "__main__":
    sys.exit(main())
