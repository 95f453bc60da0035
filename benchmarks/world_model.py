"""World model reuse: the MuJoCo model of a flight built on the first flight over
a world and reused (copied) on the next ones (``airframe/model_cache.py``).

For urban worlds of 0, 500 and 3,000 people, prints the time to build a flight's
model and MjData (``mission.assemble.place``) on the first flight and on the
second, and the cache's build count after both (1: the second did not rebuild).
Median of --repeat rounds, each starting from an empty cache.

    python benchmarks/world_model.py [--repeat 3] [--people 0 500 3000]
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import pytest_flockai as fa
from pytest_flockai.airframe import model_cache
from pytest_flockai.mission.assemble import place
from pytest_flockai.mission.plan import resolve


def plan(world):
    return resolve(fa.Mission(fa.drone("dji-mavic-2-pro"), fa.pilots.Hover(2.0), world=world, until=1.0))


def timed_build(p) -> float:
    t0 = time.perf_counter()
    place([p])
    return time.perf_counter() - t0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--people", type=int, nargs="+", default=[0, 500, 3000])
    a = ap.parse_args(argv)
    print(f"world model reuse: dji-mavic-2-pro over World.urban(size=(400, 400)), "
          f"median of {a.repeat}; load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs")
    print(f"{'people':>7s} {'1st flight (ms)':>16s} {'2nd flight (ms)':>16s} {'speed-up':>9s} "
          f"{'builds':>7s} {'model MB':>9s}")
    for n in a.people:
        world = fa.World.urban(seed=1, size=(400.0, 400.0), people=n)
        p = plan(world)
        firsts, seconds = [], []
        for _ in range(a.repeat):
            model_cache.clear()
            firsts.append(timed_build(p))
            seconds.append(timed_build(plan(world)))
        info = model_cache.info()
        f, s = statistics.median(firsts), statistics.median(seconds)
        print(f"{n:7d} {1e3 * f:16.1f} {1e3 * s:16.1f} {f / s:8.1f}x {info['builds']:7d} "
              f"{info['bytes'] / 1e6:9.1f}")


if __name__ == "__main__":
    main()
