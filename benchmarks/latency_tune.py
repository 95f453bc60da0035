"""Choose the latency model's efficiencies on the TUNING half of the published table (issue 34).

Reads ``pytest_flockai/compute/data/published_latency.csv`` and ``latency_sources.csv``
(each source assigned to the ``tuning`` or ``heldout`` half before any efficiency was
chosen) and the networks' per-node costs (``data/networks/``), fits the few shared
efficiencies on the tuning rows only (the procedure: ``pytest_flockai/compute/tuning.py``),
chooses the rule for deployments without tuning rows by leaving each tuned group out in
turn (``tuning.fallback_cv``, tuning rows only; about two minutes), scores each board
with a fit that never saw it (``tuning.loco``: the band of a team's own computer),
then writes ``pytest_flockai/compute/data/latency_efficiencies.json``: the parameters, the
fit's statistics, the tuning and held-out ratios predicted/published, and the held-out
ranges per computer/runtime that ``predict_latency(...).band`` reports. The held-out rows
are evaluated after the fit and never fed back into it.

    python benchmarks/latency_tune.py [--out FILE]
    python benchmarks/latency_tune.py --loso     # judge a model change: leave each tuning
                                                 # source out in turn (about 1 min), no write
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from pytest_flockai._io import atomic_write
from pytest_flockai.compute import predict, published, tuning


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(predict.EFFICIENCIES))
    ap.add_argument("--networks", default=str(published.NETWORKS),
                    help="folder of the per-node network summaries")
    ap.add_argument("--loso", action="store_true",
                    help="print the leave-one-source-out figures of the tuning half and stop")
    a = ap.parse_args(argv)
    rows, skipped = published.load_rows(networks=Path(a.networks))
    if not any(r.half == "tuning" for r in rows):
        print("no usable tuning rows:", *skipped[:10], sep="\n  ")
        return 1
    if a.loso:
        cv = tuning.loso(rows)
        print("leave-one-source-out on the tuning half (median |ln(predicted/published)|):")
        for src, v in cv["per_source"].items():
            print(f"  {src:44s} rows {v['n']:3d}  {v['median_abs_ln']:.3f}")
        print(f"median over sources {cv['median_of_sources']:.3f}; pooled rows: median "
              f"{cv['pooled_median']:.3f}, mean {cv['pooled_mean']:.3f}")
        return 0
    table = tuning.tune(rows)
    # the rule for deployments without tuning rows, chosen on the tuning half (about 2 min)
    table["fallback"] = tuning.fallback_cv(rows)
    table["procedure"] = ("fitted on the tuning half only (benchmarks/latency_tune.py, "
                          "pytest_flockai/compute/tuning.py); held-out evaluated after the fit")
    table["rows"] = {"tuning": sum(r.half == "tuning" for r in rows),
                     "heldout": sum(r.half == "heldout" for r in rows), "skipped": len(skipped)}
    table["bands"] = published.bands(rows, table)
    # computers never tuned (a team's own datasheet): leave each board out of the fit in turn
    cv = tuning.loco(rows, table["fallback"])
    table["bands"].update(tuning.loco_bands(cv))
    table["loco"] = {"per_board": cv["per_board"], "all": cv["all"]}
    table["tuned_computers"] = tuning.tuned_computers(rows)
    s = published.summary(rows, table)
    table["validation"] = {h: v["all"] for h, v in s.items()}
    text = json.dumps(table, indent=1, sort_keys=True) + "\n"
    atomic_write(Path(a.out), lambda fh: fh.write(text))
    for half, v in s.items():
        al = v["all"]
        print(f"{half:8s} n={al['n']:3d} median ratio {al['median_ratio']:.2f} "
              f"median |ln| {al['median_abs_ln']:.3f} worst {al['worst_ratio']:.2f} "
              f"within 2x {al['within_2x']}/{al['n']}")
    print("a board never tuned (leave-one-computer-out, median |ln|, within 2x): " + "; ".join(
        f"{b} " + ", ".join(f"{h} {v['median_abs_ln']:.3f} {v['within_2x']}/{v['n']}"
                            for h, v in hv.items())
        for b, hv in {**table["loco"]["per_board"], "all": table["loco"]["all"]}.items()))
    fb = table["fallback"]
    print("untuned deployments (leave-one-group-out on the tuning half, median |ln|): "
          + ", ".join(f"{c['rule']['scale']}/{c['rule']['dispatch']} {c['median_abs_ln']:.3f}"
                      for c in fb["candidates"]) + f"; chosen {fb['rule']}")
    print(f"wrote {a.out} ({len(skipped)} rows skipped)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
