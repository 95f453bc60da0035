"""Sweep throughput on CPU: 30-minute Mavic 2 Pro missions flown by ``fa.sweep``
across processes (workers=1 and 2) against a plain loop of ``Mission.run``.

Each variant is the flight_core benchmark's ZigZag survey, cut at ``--seconds``
of simulated time (default 1800: 30 minutes), over a payload axis. Prints, per
way of flying: variants, wall time, drone-seconds per wall second (simulated
seconds of all variants / wall time) and variants per minute. The sweep's
process start-up (spawn, importing MuJoCo) is included in its wall time.

    python benchmarks/sweep.py [--variants 4] [--seconds 1800]
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

import pytest_flockai as fa


def base(seconds: float) -> fa.Mission:
    pilot = fa.pilots.ZigZag(area=((0, 0), (600, 600)), altitude=30, spacing=25, speed=8)
    return fa.Mission(fa.drone("dji-mavic-2-pro"), pilot, seed=1, until=seconds)


def plain_loop(seconds: float, payloads) -> tuple[float, float]:
    t0 = time.perf_counter()
    sim = 0.0
    for p in payloads:
        m = base(seconds)
        m.drone.payload_kg = float(p)
        sim += m.run().sim_time_s
    return time.perf_counter() - t0, sim


def swept(seconds: float, payloads, workers: int) -> tuple[float, float]:
    t0 = time.perf_counter()
    df = fa.sweep(base(seconds), payload_kg=list(payloads), workers=workers)
    assert df["error"].isna().all(), df["error"]
    return time.perf_counter() - t0, float(df["sim_time_s"].sum())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--variants", type=int, default=4)
    ap.add_argument("--seconds", type=float, default=1800.0)
    a = ap.parse_args()
    payloads = np.linspace(0.0, 0.3, a.variants)
    print(f"{a.variants} variants of a {a.seconds:g} s Mavic 2 Pro ZigZag mission "
          f"(payload 0 to 0.3 kg) on {os.cpu_count()} CPU core(s)")
    print(f"{'way':<22}{'wall s':>9}{'drone-s/s':>12}{'variants/min':>14}")
    for name, run in (("Mission.run loop", lambda: plain_loop(a.seconds, payloads)),
                      ("fa.sweep workers=1", lambda: swept(a.seconds, payloads, 1)),
                      ("fa.sweep workers=2", lambda: swept(a.seconds, payloads, 2))):
        wall, sim = run()
        print(f"{name:<22}{wall:>9.1f}{sim / wall:>12.0f}{a.variants / wall * 60:>14.1f}",
              flush=True)


if __name__ == "__main__":
    main()
