"""Every benchmark in one table.

- flight core: 30-minute Mavic ZigZag mission RTF, bare MuJoCo RTF, ratio;
- camera: rendered frames/s at 160x120, 320x240, 640x480 (urban world);
- each example scenario flown to battery depletion: simulated time, wall time, RTF;
- the example suite's wall time (``pytest example_tests -n 2``).

    python benchmarks/run_all.py [--quick]
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(ROOT / "example_tests"))

import camera as cam_bench  # noqa: E402
import flight_core  # noqa: E402
import scenarios  # noqa: E402

import pytest_flockai as fa  # noqa: E402


def machine() -> str:
    """The machine and its load, printed with the table (figures depend on both)."""
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    load = " / ".join(f"{x:.2f}" for x in os.getloadavg()) if hasattr(os, "getloadavg") else "n/a"
    return (f"machine: {cpu}, {os.cpu_count()} CPUs, Python {platform.python_version()}; "
            f"load average (1/5/15 min) at the end: {load}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="one repeat, skip the example suite")
    a = ap.parse_args(argv)
    rep = 1 if a.quick else 3
    rows = []
    flight_core.mission(5.0).run()
    core = [flight_core.mission(1800.0).run() for _ in range(rep)]
    bare = [flight_core.bare_rtf("dji-mavic-2-pro", 300.0, False) for _ in range(rep)]
    m_rtf, b_rtf = statistics.median(r.rtf for r in core), statistics.median(bare)
    rows += [("flight core: 30 min Mavic ZigZag, mission RTF", f"{m_rtf:.0f}x"),
             ("flight core: wall time for 1800 s", f"{statistics.median(r.wall_time_s for r in core):.2f} s"),
             ("flight core: bare mj_step RTF (same model, dt)", f"{b_rtf:.0f}x"),
             ("flight core: ratio bare / mission", f"{b_rtf / m_rtf:.2f}")]
    urban = fa.World.urban(seed=0, size=(200.0, 200.0), people=100, crowds=[(60.0, 40.0, 50, 5.0)])
    for w, h in ((160, 120), (320, 240), (640, 480)):
        f, _ = cam_bench.fps(urban, w, h, 60)
        rows.append((f"camera: rendered frames/s at {w}x{h}", f"{f:.0f}"))
    models = {"cnn": scenarios.cnn(), "cheap": scenarios.cheap()}
    world = scenarios.world()
    for name in ("1-A", "1-B", "2", "3-B"):
        t0 = time.perf_counter()
        r = scenarios.mission(name, models, full=True, w=world).run()
        wall = time.perf_counter() - t0
        rows.append((f"scenario {name} to depletion: sim / wall / RTF",
                     f"{r.sim_time_s:.0f} s / {wall:.1f} s / {r.sim_time_s / wall:.0f}x"))
    if not a.quick:
        t0 = time.perf_counter()
        p = subprocess.run([sys.executable, "-m", "pytest", "example_tests", "-q", "-n", "2",
                            "-p", "no:cacheprovider"], cwd=ROOT, capture_output=True, text=True)
        last = (p.stdout.strip().splitlines() or ["?"])[-1]
        rows.append(("example suite, pytest -n 2: wall time", f"{time.perf_counter() - t0:.1f} s ({last})"))
    width = max(len(k) for k, _ in rows)
    print(machine())
    print(f"{'benchmark':<{width}}  value")
    print("-" * width + "  " + "-" * 24)
    for k, v in rows:
        print(f"{k:<{width}}  {v}")


if __name__ == "__main__":
    main()
