"""Peak memory of the largest inputs pytest-flockai accepts (issue 17).

Each scenario runs in a fresh Python process; the figure is that process's
peak resident set size (its own ``getrusage`` at the end: what ``/usr/bin/time -v``
calls "Maximum resident set size", C allocations of MuJoCo and numpy
included) and, for the Python side, the ``tracemalloc`` peak. The target:
no accepted input above 1 GiB.

    python benchmarks/limits.py            # every scenario
    python benchmarks/limits.py world      # one of them
"""

from __future__ import annotations

import subprocess
import sys

SCENARIOS = {
    "baseline": """
r = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(1.0, 5.0), until=10.0).run()
what = "crazyflie hover, 10 s (import and one small flight)"
""",
    "telemetry": """
# the telemetry store filled to limits.MAX_TELEMETRY_ROWS (flying 24 h of simulated time
# at 11.6 Hz would take hours), then turned into the DataFrame, as at the end of a flight
import numpy as np
from pytest_flockai.probes.telemetry import TelemetryRecorder
class _Battery:
    voltage_v, current_a = 15.4, 10.0
class _Meter:
    battery = _Battery()
    def totals_by_top(self):
        return {"motors": 1.0, "proc": 0.5, "comm": 0.1}
class _Data:
    act = np.zeros(6)
rec = TelemetryRecorder(fa.limits.MAX_TELEMETRY_ROWS, 6, _Meter(), _Data())
q, v, sp, w = [0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0], [0.0] * 6, [0.0] * 10, [0.0] * 3
for i in range(fa.limits.MAX_TELEMETRY_ROWS):
    rec.record(i * 0.1, q, v, sp, w, 1, 1, 100.0, float(i), 1e9)
tel = rec.frame()
what = f"telemetry at the limit: {len(tel):,} rows x {tel.shape[1]} columns"
""",
    "world": """
L = fa.limits
w = fa.World.urban(size=(L.MAX_WORLD_SIDE_M, L.MAX_WORLD_SIDE_M), people=L.MAX_PEOPLE,
                   vehicles=L.MAX_VEHICLES)
r = fa.Mission(fa.drone("dji-mavic-2-pro"), fa.pilots.Hover(10.0, 1.0), world=w, until=2.0).run()
what = (f"World.urban {L.MAX_WORLD_SIDE_M:g} m x {L.MAX_WORLD_SIDE_M:g} m, {len(w.people):,} people, "
        f"{L.MAX_VEHICLES:,} vehicles, {len(w.buildings):,} buildings, flown 2 s")
""",
    "zigzag": """
L = fa.limits
p = fa.pilots.ZigZag(((0, 0), (50.0, 0.5 * (L.MAX_WAYPOINTS / 2 - 3))), altitude=10, spacing=0.5)
r = fa.Mission(fa.drone("dji-mavic-2-pro"), p, until=5.0).run()
what = f"ZigZag at limits.MAX_WAYPOINTS: {len(p.points):,} points, flown 5 s"
""",
    "long-flight": """
d = fa.drone("dji-mavic-2-pro")
r = fa.Mission(d, fa.pilots.Hover(10.0), until="battery_depleted").run()
what = (f"Mavic hover until the battery is depleted: {r.sim_time_s / 60:.1f} min simulated, "
        f"{len(r.telemetry):,} telemetry rows")
""",
    "sweep": """
# a sweep at limits.MAX_VARIANTS: its plan (random design, three axes) and one row per
# variant (a real flight's row, copied), turned into the DataFrame with a budget; flying
# them all would take hours
from pytest_flockai.sweeps import design, runner
from pytest_flockai import budgets
L = fa.limits
plan, _ = design.variants({"payload_kg": (0.0, 0.01), "wind_mps": (0.0, 5.0),
                           "mission_seed": (0, 1000)}, "random", L.MAX_VARIANTS, 0)
m = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(1.0, 1.0))
row = runner.sweep(m, payload_kg=[0.0], workers=1).iloc[0].to_dict()
rows = [{**row, **v} for v in plan]
df = runner.frame(rows, list(plan[0]), budgets.parse_many({"flight_time_s": ">= 1 s"}))
what = f"sweep at limits.MAX_VARIANTS: {len(df):,} variants' plan, rows and DataFrame"
""",
}

CHILD = """
import os, resource, sys, time, tracemalloc
os.environ.setdefault("MUJOCO_GL", "egl")
# a guard for the machine: an allocation past 4 GiB fails here instead of swapping
resource.setrlimit(resource.RLIMIT_AS, (4 << 30, 4 << 30))
tracemalloc.start()
t0 = time.perf_counter()
import pytest_flockai as fa
{body}
wall = time.perf_counter() - t0
rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0   # KiB on Linux
print(f"{{rss:.0f}}\\t{{tracemalloc.get_traced_memory()[1] / 2**20:.0f}}\\t{{wall:.1f}}\\t{{what}}")
"""


def run(name: str) -> tuple[float, str]:
    proc = subprocess.run([sys.executable, "-c", CHILD.format(body=SCENARIOS[name])],
                          capture_output=True, text=True)
    if proc.returncode:
        err = proc.stderr.strip()
        return float("nan"), f"FAILED: {err.splitlines()[-1] if err else '?'}"
    rss, py_peak, wall, what = proc.stdout.strip().splitlines()[-1].split("\t")
    rss = float(rss)
    return rss, f"{rss:7.0f} MiB RSS  {float(py_peak):6.0f} MiB Python  {float(wall):7.1f} s  {what}"


def main(argv) -> int:
    names = argv or list(SCENARIOS)
    worst = 0.0
    for name in names:
        rss, line = run(name)
        worst = max(worst, rss) if rss == rss else worst
        print(f"{name:12s} {line}", flush=True)
    print(f"largest peak RSS: {worst:.0f} MiB (target: below 1024 MiB)")
    return 0 if worst < 1024 else 1


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
