"""Sweep throughput of the batched (MJX/JAX) backend against the per-flight core
and the process pool, in drone-seconds per wall second and variants per minute
of 30-minute missions.

Each variant is the Mavic 2 Pro ZigZag survey of benchmarks/sweep.py over a
payload axis. Three ways:

- ``Mission.run`` loop: the per-flight core, ``--core-variants`` flights of
  ``--seconds`` (default 1800 s, 30 minutes) one after another;
- ``fa.sweep(workers=2)``: the same flights across 2 processes (spawn start-up
  included);
- ``fa.sweep(backend=--backend)`` (``jax``: the free-flight body, the default; ``mjx``:
  MJX's full physics) at each ``--batch`` size: one warm-up sweep (JIT compile or a
  load from JAX's persistent cache, printed), then a timed sweep of ``--mjx-seconds``
  per variant (``--mjx-seconds 1800``: the full thirty minutes, for a GPU)
  (default 20 s: at 30 minutes, 256 variants on 2 CPU cores would take hours);
  its rate is per drone-second, and variants per minute are for 30-minute
  missions at that rate (the batched step costs the same at every simulated
  second: a fixed-length scan, chunk after chunk).

``--device gpu`` runs the batched backend on JAX's GPU (needs jax[cuda]). The
load average is printed with every line: these machines are shared. The timed line
also splits the sweep into building the variants (numbers and MuJoCo models, on the
host) and the batch itself. On a GPU, for 10^3 to 10^5 thirty-minute variants:

    python benchmarks/sweep_mjx.py --device gpu --skip-core --mjx-seconds 1800 \
        --batch 1000 10000 100000

    python benchmarks/sweep_mjx.py [--device cpu|gpu] [--backend jax|mjx]
        [--batch 8 64 256] [--seconds 1800] [--mjx-seconds 20] [--core-variants 2]
        [--skip-core]
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

import pytest_flockai as fa
from pytest_flockai.sweeps.batched import engine

MISSION_S = 1800.0       # the figures' mission: 30 minutes


def base(seconds: float) -> fa.Mission:
    pilot = fa.pilots.ZigZag(area=((0, 0), (600, 600)), altitude=30, spacing=25, speed=8)
    return fa.Mission(fa.drone("dji-mavic-2-pro"), pilot, seed=1, until=seconds)


def _line(name, n, wall, sim, note=""):
    rate = sim / wall
    load = ", ".join(f"{x:.1f}" for x in os.getloadavg())
    print(f"{name:<30}{n:>6}{wall:>9.1f}{rate:>12.0f}{rate / MISSION_S * 60:>14.1f}"
          f"   load {load}{note}", flush=True)


def core(seconds, n):
    t0 = time.perf_counter()
    sim = 0.0
    for p in np.linspace(0.0, 0.3, n):
        m = base(seconds)
        m.drone.payload_kg = float(p)
        sim += m.run().sim_time_s
    _line("Mission.run loop (1 core)", n, time.perf_counter() - t0, sim)


def pool(seconds, n):
    t0 = time.perf_counter()
    df = fa.sweep(base(seconds), payload_kg=list(np.linspace(0.0, 0.3, n)), workers=2)
    assert df["error"].isna().all(), df["error"]
    _line("fa.sweep workers=2", n, time.perf_counter() - t0, float(df["sim_time_s"].sum()))


def batched(seconds, n, device, backend):
    payloads = list(np.linspace(0.0, 0.3, n))
    t0 = time.perf_counter()
    fa.sweep(base(min(seconds, 4.0)), payload_kg=payloads, backend=backend, device=device)
    warm = time.perf_counter() - t0
    t0 = time.perf_counter()
    df = fa.sweep(base(seconds), payload_kg=payloads, backend=backend, device=device)
    assert df["error"].isna().all(), df["error"]
    t = engine.LAST_TIMINGS
    _line(f"fa.sweep backend={backend} ({device})", n, time.perf_counter() - t0,
          float(df["sim_time_s"].sum()), f"   (variants {t['variants_s']:.1f} s, batch "
          f"{t['batch_s']:.1f} s; warm-up with JIT compile {warm:.1f} s)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--device", default="cpu", choices=("cpu", "gpu"))
    ap.add_argument("--batch", type=int, nargs="+", default=[8, 64, 256])
    ap.add_argument("--seconds", type=float, default=MISSION_S)
    ap.add_argument("--mjx-seconds", type=float, default=20.0)
    ap.add_argument("--core-variants", type=int, default=2)
    ap.add_argument("--skip-core", action="store_true", help="only the batched backend")
    ap.add_argument("--backend", default="jax", choices=("jax", "mjx"))
    a = ap.parse_args()
    print(f"Mavic 2 Pro ZigZag missions (payload 0 to 0.3 kg), {os.cpu_count()} CPU core(s); "
          f"variants/min are of {MISSION_S:g} s missions at the measured drone-s/s")
    print(f"{'way':<30}{'n':>6}{'wall s':>9}{'drone-s/s':>12}{'variants/min':>14}")
    if not a.skip_core:
        core(a.seconds, a.core_variants)
        pool(a.seconds, 2 * a.core_variants)
    for n in a.batch:
        batched(a.mjx_seconds, n, a.device, a.backend)


if __name__ == "__main__":
    main()
