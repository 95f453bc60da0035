"""Flight core speed: a 30-minute Mavic 2 Pro ZigZag mission vs a bare mj_step loop.

Prints the mission's real-time factor (simulated s per wall s), the bare
MuJoCo RTF over the same compiled model and timestep (a Python loop of
single mj_step calls, as the peers' figures in the README were measured, and the same in C-batched nstep
calls), their ratio, and peak memory. Median of --repeat runs.

    python benchmarks/flight_core.py [--repeat 5] [--seconds 1800]
"""

from __future__ import annotations

import argparse
import statistics
import time
import tracemalloc

import mujoco

import pytest_flockai as fa
from pytest_flockai.airframe.mjspec import build_model


def mission(seconds: float, blueprint: str = "dji-mavic-2-pro", probes: bool = True):
    d = fa.drone(blueprint)
    pilot = fa.pilots.ZigZag(area=((0, 0), (600, 600)), altitude=30, spacing=25, speed=8)
    off = None if probes else [cls(enabled=False) for cls in fa.probes.builtin.BUILTIN]
    return fa.Mission(d, pilot, seed=1, until=seconds, probes=off)


def bare_rtf(blueprint: str, sim_seconds: float, batched: bool) -> float:
    d = fa.drone(blueprint)
    m = build_model(d, None, physics_dt=1.0 / d.sim.physics_hz)
    data = mujoco.MjData(m)
    data.qpos[2] = 30.0                                   # in the air, as the mission mostly is
    data.ctrl[:] = d.hover_thrust_per_rotor_n
    data.act[:] = d.hover_thrust_per_rotor_n
    n = int(sim_seconds * d.sim.physics_hz)
    step = mujoco.mj_step
    t0 = time.perf_counter()
    if batched:
        k = int(round(d.sim.physics_hz / d.sim.control_hz))
        for _ in range(n // k):
            step(m, data, k)
    else:
        for _ in range(n):
            step(m, data)
    return sim_seconds / (time.perf_counter() - t0)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--seconds", type=float, default=1800.0)
    ap.add_argument("--blueprint", default="dji-mavic-2-pro")
    a = ap.parse_args(argv)
    mission(5.0, a.blueprint).run()                      # warm-up (imports, caches)
    rtfs, walls, bare_core = [], [], []
    for _ in range(a.repeat):          # interleaved, so both see the same machine load
        r = mission(a.seconds, a.blueprint).run()
        rtfs.append(r.rtf)
        walls.append(r.wall_time_s)
        bare_core.append(mission(a.seconds, a.blueprint, probes=False).run().wall_time_s)
    bare = [bare_rtf(a.blueprint, min(a.seconds, 300.0), False) for _ in range(a.repeat)]
    batched = [bare_rtf(a.blueprint, min(a.seconds, 300.0), True) for _ in range(a.repeat)]
    tracemalloc.start()
    mission(min(a.seconds, 600.0), a.blueprint).run()
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    d = fa.drone(a.blueprint)
    mr, br, bb = statistics.median(rtfs), statistics.median(bare), statistics.median(batched)
    print(f"flight core benchmark: {a.blueprint}, ZigZag, {a.seconds:g} s simulated, "
          f"physics {d.sim.physics_hz:g} Hz, control {d.sim.control_hz:g} Hz, median of {a.repeat}")
    print(f"{'measure':46s} {'value':>12s}")
    print(f"{'mission wall time (s)':46s} {statistics.median(walls):12.3f}")
    print(f"{'mission RTF (sim s / wall s)':46s} {mr:12.0f}")
    print(f"{'bare mj_step loop RTF (one call per step)':46s} {br:12.0f}")
    print(f"{'bare mj_step RTF (nstep batched per tick)':46s} {bb:12.0f}")
    print(f"{'ratio bare loop / mission':46s} {br / mr:12.2f}")
    print(f"{'ratio bare batched / mission':46s} {bb / mr:12.2f}")
    wp, wn = statistics.median(walls), statistics.median(bare_core)
    print(f"{'mission wall time, probes disabled (s)':46s} {wn:12.3f}")
    print(f"{'probe overhead at default periods':46s} {100 * (wp - wn) / wn:11.1f}%")
    print(f"{'peak traced memory, 600 s mission (MB)':46s} {peak / 1e6:12.1f}")
    print(f"runs (RTF): {', '.join(f'{x:.0f}' for x in rtfs)}")


if __name__ == "__main__":
    main()
