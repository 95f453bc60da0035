"""Fleet speed: an N-drone survey without cameras, on one core.

Flies ``fa.fleet.survey`` strips of one area with 1, 2, 4 (and 8) Mavic 2 Pro
drones, each drone surveying for about ``--minutes`` of simulated time, and
prints each fleet's real-time factor (simulated s of the fleet's clock per wall
s) and the wall cost per drone per simulated second, beside a single Mission
flying the same strip (the loop's cost without the fleet). Median of --repeat
runs. The target of issue 14: 4 drones, 10-minute survey, >= 100x real time.

    python benchmarks/fleet.py [--repeat 3] [--minutes 10] [--sizes 1 2 4 8]
"""

from __future__ import annotations

import argparse
import statistics
import time

import pytest_flockai as fa

BLUEPRINT = "dji-mavic-2-pro"
SPACING, SPEED, ALT = 25.0, 8.0, 30.0
LEGS_PER_DRONE = 6


def area_for(n: int, minutes: float):
    """An area whose strips take each drone about ``minutes`` to fly (legs along x)."""
    leg_s = minutes * 60.0 / LEGS_PER_DRONE - SPACING / SPEED - 6.0    # turns: ~6 s each
    length = max(50.0, leg_s * SPEED)
    return ((0.0, 0.0), (length, SPACING * (LEGS_PER_DRONE * n - 1)))


def fleet(n: int, minutes: float) -> fa.Fleet:
    area = area_for(n, minutes)
    parts = fa.fleet.survey(area, n, altitude=ALT, spacing=SPACING, speed=SPEED)
    return fa.Fleet([fa.FleetDrone(f"drone-{i + 1}", fa.drone(BLUEPRINT), p, pad, seed=i)
                     for i, (p, pad) in enumerate(parts)], area=area, swath_m=SPACING)


def single(minutes: float) -> fa.Mission:
    (p, pad), = fa.fleet.survey(area_for(1, minutes), 1, altitude=ALT, spacing=SPACING, speed=SPEED)
    return fa.Mission(fa.drone(BLUEPRINT), p, seed=0)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--minutes", type=float, default=10.0)
    ap.add_argument("--sizes", type=int, nargs="+", default=[1, 2, 4, 8])
    a = ap.parse_args(argv)
    fleet(2, 0.5).run()                                    # warm-up (imports, caches)
    print(f"fleet benchmark: {BLUEPRINT}, survey strips ~{a.minutes:g} min each, no cameras, "
          f"median of {a.repeat}")
    print(f"{'drones':>6s} {'sim s':>8s} {'wall s':>8s} {'RTF':>8s} {'ms wall / drone / sim min':>26s}"
          f" {'coverage':>9s}")
    t_single = []
    for _ in range(a.repeat):
        t0 = time.perf_counter()
        r = single(a.minutes).run()
        t_single.append((r.sim_time_s, time.perf_counter() - t0))
    sim, wall = statistics.median(s for s, _ in t_single), statistics.median(w for _, w in t_single)
    print(f"{'Mission':>6s} {sim:8.0f} {wall:8.2f} {sim / wall:8.0f} {1e3 * wall / (sim / 60):26.1f}"
          f" {'':>9s}")
    for n in a.sizes:
        runs = []
        for _ in range(a.repeat):
            t0 = time.perf_counter()
            r = fleet(n, a.minutes).run()
            runs.append((r.kpis["fleet.makespan_s"], time.perf_counter() - t0,
                         r.kpis["fleet.coverage_fraction"], r.kpis["fleet.crashes"]))
        sim = statistics.median(x[0] for x in runs)
        wall = statistics.median(x[1] for x in runs)
        per = 1e3 * wall / n / (sim / 60)
        print(f"{n:6d} {sim:8.0f} {wall:8.2f} {sim / wall:8.0f} {per:26.1f} "
              f"{runs[0][2]:9.3f}" + ("  CRASHES" if runs[0][3] else ""))


if __name__ == "__main__":
    main()
