"""The sweep engine's cost: drone-seconds simulated per wall second of one sweep
(Crazyflie hovers of ``--seconds`` s, ``--variants`` of them), per engine, in
one interleaved run (each measurement in a fresh Python process, engines
alternating round by round, so that other jobs on the machine hit all alike).

    python benchmarks/sweep_engine.py                       # this checkout's engines
    python benchmarks/sweep_engine.py --old ../main         # and workers=N of another checkout

Engines: ``workers=1`` (in this process), ``workers=N`` (the sweep's own spawned
pool, its start included), ``executor=LocalCluster`` (a Dask cluster of N
single-thread worker processes started before the clock starts: the cost of the
tasks, not of the cluster), and with ``--old`` the ``workers=N`` of the other
checkout. Prints the median of the rounds and the ratio to ``workers=N``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent.parent

CHILD = """
import time, sys
import pytest_flockai as fa
from pytest_flockai.cache import caching
engine, n, seconds, workers = sys.argv[1], int(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4])
if __name__ == "__main__":
    m = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=1.0))
    kw = dict(payload_kg=[0.0, 0.002, 0.004, 0.006], mission_seed=list(range(n // 4)),
              until=[seconds])
    cluster = None
    if engine == "dask":
        from distributed import Client, LocalCluster
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, dashboard_address=None)
        client = Client(cluster)
        kw["executor"] = client
    else:
        kw["workers"] = 1 if engine == "one" else workers
    with caching(None):
        t = time.perf_counter()
        df = fa.sweep(m, **kw)
        wall = time.perf_counter() - t
    assert df["error"].isna().all(), df["error"].dropna().tolist()
    print(df["sim_time_s"].sum() / wall)
    if cluster is not None:
        client.close()
        cluster.close()
"""


def measure(root: Path, engine: str, args) -> float:
    env = dict(os.environ, PYTHONPATH=str(root), MUJOCO_GL="egl")
    out = subprocess.run([sys.executable, "-c", CHILD, engine, str(args.variants),
                          str(args.seconds), str(args.workers)], capture_output=True, text=True,
                         env=env, cwd=root, check=False)
    if out.returncode:
        raise SystemExit(f"{engine} at {root} failed:\n{out.stderr[-2000:]}")
    return float(out.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--variants", type=int, default=32)
    p.add_argument("--seconds", type=float, default=10.0)
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--old", type=Path, default=None, help="another checkout (e.g. of main)")
    args = p.parse_args(argv)
    engines = [("workers=1", HERE, "one"), (f"workers={args.workers}", HERE, "pool"),
               ("dask LocalCluster", HERE, "dask")]
    if args.old is not None:
        engines.append((f"old workers={args.workers}", args.old.resolve(), "pool"))
    figures: dict = {name: [] for name, _, _ in engines}
    for _ in range(args.rounds):
        for name, root, engine in engines:
            figures[name].append(measure(root, engine, args))
    with open("/proc/loadavg") as fh:
        load = fh.read().split()[:3]
    print(f"{args.variants} Crazyflie hovers of {args.seconds:g} s, median of {args.rounds} "
          f"interleaved rounds; load average {' '.join(load)}")
    ref = statistics.median(figures[f"workers={args.workers}"])
    for name, values in figures.items():
        med = statistics.median(values)
        print(f"  {name:22s} {med:8.0f} drone-s/s   x{med / ref:5.2f} of workers={args.workers}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
