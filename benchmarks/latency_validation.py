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


def verdicts(s: dict) -> list[dict]:
    """Per computer with at least ``MIN_ROWS`` held-out rows: the two criteria of the target
    (median |ln| <= ln 1.25; every row within 2x) and PASS only when both hold."""
    out = []
    for name, st in s.get("heldout", {}).get("computer", {}).items():
        if st["n"] < MIN_ROWS:
            continue
        med_ok = st["median_abs_ln"] <= MEDIAN_BOUND
        all_ok = st["within_2x"] == st["n"]
        out.append({"computer": name, "n": st["n"], "median_abs_ln": st["median_abs_ln"],
                    "median_ok": med_ok, "worst_ratio": st["worst_ratio"],
                    "within_2x": st["within_2x"], "within_2x_ok": all_ok,
                    "verdict": "PASS" if med_ok and all_ok else "FAIL"})
    return out


def verdict_lines(s: dict) -> list[str]:
    """The held-out target per computer, as Markdown."""
    out = [f"| computer (held-out rows >= {MIN_ROWS}) | rows | median abs ln (<= "
           f"{MEDIAN_BOUND:.3f}) | worst ratio | within 2x (all) | verdict |",
           "|---|---|---|---|---|---|"]
    for v in verdicts(s):
        out.append(f"| {v['computer']} | {v['n']} | {v['median_abs_ln']:.3f} "
                   f"{'ok' if v['median_ok'] else 'over'} | {v['worst_ratio']:.2f} | "
                   f"{v['within_2x']}/{v['n']} {'ok' if v['within_2x_ok'] else 'not all'} | "
                   f"**{v['verdict']}** |")
    n_pass = sum(v["verdict"] == "PASS" for v in verdicts(s))
    out.append(f"\n{n_pass} of {len(verdicts(s))} computers meet the held-out target.")
    return out


def fresh_lines(rows, table) -> list[str]:
    """The rows of the sources added last (``Row.added``), per half and computer: the
    held-out ones among them were never seen by a revision of the model made before they
    were added."""
    if not rows:
        return []
    last = max(r.added for r in rows)
    new = [r for r in rows if r.added == last]
    if not new:
        return []
    s = published.summary(new, table)
    out = [f"Rows of the sources added on {last} ({len(new)} rows; their held-out rows were "
           f"seen by no revision of the model made before they were added):", "",
           "| half | computer | rows | median abs ln | worst ratio | within 2x |",
           "|---|---|---|---|---|---|"]
    for half, v in s.items():
        for name, st in v.get("computer", {}).items():
            out.append(f"| {half} | {name} | {st['n']} | {st['median_abs_ln']:.3f} | "
                       f"{st['worst_ratio']:.2f} | {st['within_2x']}/{st['n']} |")
        al = v["all"]
        out.append(f"| {half} | all | {al['n']} | {al['median_abs_ln']:.3f} | "
                   f"{al['worst_ratio']:.2f} | {al['within_2x']}/{al['n']} |")
    return out


def loco_lines(table: dict, s: dict) -> list[str]:
    """A board never tuned (``tuning.loco``, stored by latency_tune.py): each board predicted
    by a fit that left it out, against the same rows predicted by the full fit."""
    loco = table.get("loco") or {}
    if not loco:
        return []
    board = published.BOARD
    out = ["A board never tuned (leave-one-computer-out: fitted without any row of that board, "
           "its power modes included; what a team's own datasheet, fa.compute.computer, gets):",
           "", "| board | half | rows | median abs ln, never tuned | within 2x | median abs ln, "
           "tuned (its computers) |", "|---|---|---|---|---|---|"]
    for b, halves in {**loco["per_board"], "all boards": loco["all"]}.items():
        for half in ("tuning", "heldout"):
            if half not in halves:
                continue
            v = halves[half]
            tuned = ([s[half]["all"]] if b == "all boards" else
                     [st for name, st in s.get(half, {}).get("computer", {}).items()
                      if board.get(name, name) == b])
            t = (f"{tuned[0]['median_abs_ln']:.3f}" if len(tuned) == 1 else
                 ", ".join(f"{st['median_abs_ln']:.3f}" for st in tuned) or "-")
            out.append(f"| {b} | {half} | {v['n']} | {v['median_abs_ln']:.3f} | "
                       f"{v['within_2x']}/{v['n']} | {t} |")
    return out


def table_lines(s: dict) -> list[str]:
    out = ["| half | by | name | rows | median ratio | median abs ln | worst ratio | within 2x | "
           "target met |", "|---|---|---|---|---|---|---|---|---|"]
    for half, v in s.items():
        for by in ("computer", "runtime", "computer/runtime"):
            for name, st in v[by].items():
                met = ""
                if by == "computer" and st["n"] >= MIN_ROWS:
                    ok = st["median_abs_ln"] <= MEDIAN_BOUND and st["within_2x"] == st["n"]
                    met = "PASS" if ok else "FAIL"
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
    print("\nTarget on the held-out half, per computer with at least "
          f"{MIN_ROWS} held-out rows: median |ln(predicted/published)| <= ln 1.25 and no "
          "row beyond 2x:")
    vlines = verdict_lines(s)
    print("\n".join(vlines))
    fresh = fresh_lines(rows, table)
    if fresh:
        print()
        print("\n".join(fresh))
    loco = loco_lines(table, s)
    if loco:
        print()
        print("\n".join(loco))
    if a.rows:
        for r, q in zip(rows, published.ratios(rows, table)):
            print(f"{r.half:8s} {r.row_id:>6s} {r.computer:24s} {r.group:26s} "
                  f"{r.network}-{r.input:5s} published {1e3 * r.latency_s:9.2f} ms  "
                  f"predicted/published {q:6.2f}")
    print("\nEnergy per inference against the published watt-meter figures "
          "(predicted latency x busy power, whole board; on a CPU the busy power above idle "
          "x threads / cores). Beside it: the latency's ratio, and where the source gives "
          "the idle power, the power above idle alone (predicted / measured W), so a miss "
          "shows whether the latency or the power caused it:")
    checked = []
    for e in published.energy_check(table, networks=Path(a.networks)):
        if "skipped" in e:
            print(f"  {e['id']}: skipped ({e['skipped']})")
            continue
        ok = 0.5 <= e["ratio"] <= 2.0
        checked.append(ok)
        idle = (f", above idle ratio {e['above_idle_ratio']:.2f} (latency "
                f"{e['latency_ratio']:.2f} x power above idle {e['power_above_idle_ratio']:.2f})"
                if "above_idle_ratio" in e else f" (latency {e['latency_ratio']:.2f})")
        print(f"  {e['id']}: {e['computer']} {e['deployment']} {e['network']}: published "
              f"{e['published_j']:.3f} J, predicted {e['predicted_j']:.3f} J, ratio "
              f"{e['ratio']:.2f}{idle}: {'within 2x' if ok else 'BEYOND 2x'}")
    print(f"  energy within 2x of the published figure: {sum(checked)}/{len(checked)} rows "
          f"({'PASS' if checked and all(checked) else 'FAIL'})")
    print(f"{len(rows)} rows used, {len(skipped)} skipped")
    for why in skipped:
        print("  skipped", why)
    if a.markdown:
        text = "\n".join(lines + [""] + vlines + ([""] + fresh if fresh else [])) + "\n"
        atomic_write(Path(a.markdown), lambda fh: fh.write(text))
    return 0


if __name__ == "__main__":
    sys.exit(main())
