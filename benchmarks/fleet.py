"""Fleet speed: an N-drone survey without cameras, on one core.

Flies ``fa.fleet.survey`` strips of one area with 1, 2, 4 (and 8) Mavic 2 Pro
drones, each drone surveying for about ``--minutes`` of simulated time, and
prints each fleet's real-time factor (simulated s of the fleet's clock per wall
s), the same from the process's CPU time (``time.process_time``: what one
core spends on it, less sensitive to other jobs on a shared machine) and the
CPU cost per drone per simulated minute, beside a single Mission flying the
same strip (the loop's cost without the fleet). Median of --repeat runs; the
load average is printed with the table. The target of issue 14: 4 drones, 10-minute survey, >= 100x real time.

    python benchmarks/fleet.py [--repeat 3] [--minutes 10] [--sizes 1 2 4 8]
"""

from __future__ import annotations

import argparse
import os
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
    return fa.Fleet([fa.FleetDrone(f"drone-{i + 1}", fa.drone(BLUEPRINT), p, pad=pad, seed=i)
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
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs")
    print(f"{'drones':>7s} {'sim s':>6s} {'wall s':>7s} {'RTF wall':>9s} {'RTF CPU':>8s} "
          f"{'CPU ms / drone / sim min':>25s} {'coverage':>9s}")
    _row("Mission", [_timed(lambda: single(a.minutes).run(), lambda r: r.sim_time_s)
                     for _ in range(a.repeat)], 1)
    for n in a.sizes:
        _row(str(n), [_timed(lambda n=n: fleet(n, a.minutes).run(),
                             lambda r: r.kpis["fleet.makespan_s"], "fleet.coverage_fraction")
                      for _ in range(a.repeat)], n)


def _timed(fly, sim_of, cov=None):
    w0, c0 = time.perf_counter(), time.process_time()
    r = fly()
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    return sim_of(r), wall, cpu, (r.kpis[cov] if cov else None)


def _row(label, runs, n):
    sim = statistics.median(x[0] for x in runs)
    wall = statistics.median(x[1] for x in runs)
    cpu = statistics.median(x[2] for x in runs)
    cov = runs[0][3]
    print(f"{label:>7s} {sim:6.0f} {wall:7.2f} {sim / wall:9.0f} {sim / cpu:8.0f} "
          f"{1e3 * cpu / n / (sim / 60):25.1f} {'' if cov is None else f'{cov:.3f}':>9s}")


if __name__ == "__main__":
    main()
