"""The flight cache on the example suite: cold and warm wall time by worker count.

    MUJOCO_GL=egl python benchmarks/flight_cache.py            # -n 1 cold, -n 2 cold, -n 2 warm
    MUJOCO_GL=egl python benchmarks/flight_cache.py 1 2 4 8 16 # cold at each -n, warm at the last

Each cold run starts from an empty cache directory (``-o cache_dir=...``, a
fresh temporary folder); the warm run repeats the last cold run's command on
the cache it filled. Prints wall seconds, the warm speed-up, the flights the
cache served, and the slowest tests of the warm run (what the cache and its memo
of views, inference and scores do not cover).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def run(workers: int, cache_dir: Path, report: Path) -> tuple[float, str]:
    cmd = [sys.executable, "-m", "pytest", "example_tests", "-q", "-p", "no:randomly",
           "-o", f"cache_dir={cache_dir}", "--flockai-json", str(report), "--durations=4"]
    if workers > 1:
        cmd += ["-n", str(workers)]
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True,
                          env={**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")})
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        sys.exit(f"pytest failed ({proc.returncode}):\n{proc.stdout[-3000:]}\n{proc.stderr[-2000:]}")
    return wall, proc.stdout


def cache_counts(report: Path) -> dict:
    doc = json.loads(report.read_text())
    counts: dict = {}
    seen = set()
    for t in doc["tests"]:
        for f in t["flights"]:
            c = f.get("cache") or {}
            ident = c.get("key") or id(f)
            if ident in seen:       # a session fixture's flight is listed by every test using it
                continue
            seen.add(ident)
            counts[c.get("status")] = counts.get(c.get("status"), 0) + 1
    return counts


def main(argv: list[str]) -> None:
    workers = [int(a) for a in argv] or [1, 2]
    print(f"example suite, {os.cpu_count()} CPU(s) on this machine, load average "
          f"{os.getloadavg()[0]:.1f} at the start (other jobs slow every figure alike)")
    print(f"{'run':<14}{'wall s':>9}  cache")
    cold = {}
    with tempfile.TemporaryDirectory() as tmp:
        for n in workers:
            cache = Path(tmp) / f"cache-n{n}"
            wall, _ = run(n, cache, Path(tmp) / "r.json")
            cold[n] = wall
            print(f"{f'-n {n} cold':<14}{wall:9.1f}  {cache_counts(Path(tmp) / 'r.json')}",
                  flush=True)
        n = workers[-1]
        wall, out = run(n, Path(tmp) / f"cache-n{n}", Path(tmp) / "r.json")
        print(f"{f'-n {n} warm':<14}{wall:9.1f}  {cache_counts(Path(tmp) / 'r.json')}")
    print(f"warm speed-up at -n {n}: {cold[n] / wall:.1f}x (cold {cold[n]:.1f} s / warm {wall:.1f} s);"
          f" load average now {os.getloadavg()[0]:.1f}")
    if len(cold) > 1 and 1 in cold:
        for k, v in cold.items():
            if k != 1:
                print(f"cold -n {k} vs -n 1: {cold[1] / v:.2f}x")
    lines = out.splitlines()
    start = next((i for i, s in enumerate(lines) if "slowest" in s), None)
    if start is not None:
        print("slowest tests of the warm run (not flights):")
        for s in lines[start + 1:start + 5]:
            print("  " + s)


if __name__ == "__main__":
    main(sys.argv[1:])
