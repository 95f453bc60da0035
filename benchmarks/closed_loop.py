"""Closed-loop speed: a follow flight with the oracle, and with the shipped detector.

A Mavic 2 Pro hovers at 20 m and follows a person walking 60 m and turning
(``fa.actors.walk_and_turn``); the flight lasts --seconds of simulated time after
the 12 s climb. Printed, each the median of --repeat runs: the real-time factor
(simulated s per wall s, and per CPU s of this process: less sensitive to other
jobs on a shared machine) of

- the same flight without task or policy (the loop's own cost),
- ``fa.ml.Oracle`` at 5 Hz + ``fa.policy.Follow`` (nothing is rendered; the
  target of issue 25 is >= 100x),
- the shipped detector (fixtures/models/detector.onnx) at 5 Hz on 320 x 240 frames
  + Follow, with where its time goes (cProfile of one more run, cumulative
  seconds in rendering, ONNX Runtime, the frame truth, the policy, MuJoCo physics);
- a fleet of 4 surveying with an oracle task each, with and without a
  ``fa.policy.SharedSearch`` per drone, over a world without people, so the
  policies step, read every delivered result and never act: their own cost, as
  CPU seconds per simulated drone-second (target of issue 25: within 10 %).

    python benchmarks/closed_loop.py [--repeat 3] [--seconds 60]
"""

from __future__ import annotations

import argparse
import cProfile
import os
import pstats
import statistics
import time
from pathlib import Path

import pytest_flockai as fa

DETECTOR = Path(__file__).resolve().parent.parent / "fixtures" / "models" / "detector.onnx"
CLIMB_S = 12.0
BUCKETS = {"render": "render_pose", "onnx runtime": "run", "frame truth": "truth",
           "policy": "step"}
FILES = {"render": "sensors/camera.py", "onnx runtime": "ml/models.py",
         "frame truth": "world/truth.py", "policy": "policy/base.py"}


def mission(kind: str, seconds: float) -> fa.Mission:
    walker = fa.actors.walk_and_turn(start=(3.0, 0.0), start_s=CLIMB_S, first_m=60.0,
                                     turn_deg=90.0, then_m=40.0, name="alice")
    tasks, policies = [], []
    if kind != "none":
        model = (fa.ml.Oracle(classes=["person"]) if kind == "oracle"
                 else fa.ml.OnnxModel(DETECTOR, name="detector"))
        tasks = [fa.Task(model, period_s=0.2, evaluate="detection", score_threshold=0.4,
                         name="eye")]
        policies = [fa.policy.Follow("eye", score="alice")]
    return fa.Mission(fa.drone("dji-mavic-2-pro"), fa.pilots.Hover(altitude=20.0),
                      world=fa.World.scene(size=(300.0, 300.0)), tasks=tasks, actors=[walker],
                      policies=policies, until=CLIMB_S + seconds)


def timed(kind: str, seconds: float, repeat: int):
    m = mission(kind, seconds)
    m.run()                                   # warm: imports, GL context, ONNX session
    wall, cpu = [], []
    for _ in range(repeat):
        w0, c0 = time.perf_counter(), time.process_time()
        res = m.run()
        wall.append(time.perf_counter() - w0)
        cpu.append(time.process_time() - c0)
    t = res.kpis["flight_time_s"]
    return t / statistics.median(wall), t / statistics.median(cpu), res


def where_time_goes(seconds: float) -> dict:
    m = mission("detector", seconds)
    m.run()
    prof = cProfile.Profile()
    prof.enable()
    w0 = time.perf_counter()
    m.run()
    total = time.perf_counter() - w0
    prof.disable()
    stats = pstats.Stats(prof).stats
    out = {"total (profiled)": total}
    for bucket, fn in BUCKETS.items():
        out[bucket] = sum(v[3] for (f, _, name), v in stats.items()
                          if name == fn and f.endswith(FILES[bucket]))
    out["mujoco physics"] = sum(v[3] for (f, _, name), v in stats.items() if "mj_step" in name)
    return out


def fleet(policies: bool) -> fa.Fleet:
    area = ((-60.0, -60.0), (60.0, 60.0))
    station = fa.policy.GroundStation()
    drones = []
    for i, (pilot, pad) in enumerate(fa.fleet.survey(area, 4, altitude=20.0, spacing=15.0,
                                                     speed=6.0)):
        eye = fa.Task(fa.ml.Oracle(classes=["person"]), period_s=0.2, evaluate="detection",
                      name="eye")
        pol = [fa.policy.SharedSearch("eye", station)] if policies else []
        drones.append(fa.FleetDrone(f"d{i + 1}", fa.drone("dji-mavic-2-pro"), pilot, pad=pad,
                                    tasks=[eye], seed=i, policies=pol))
    return fa.Fleet(drones, world=fa.World.scene(size=(140.0, 140.0)))


def fleet_cost(repeat: int) -> dict:
    """CPU s per simulated drone-second of the fleet, without and with policies,
    interleaved runs (median)."""
    out: dict = {False: [], True: []}
    for f in (fleet(False), fleet(True)):
        f.run()                                          # warm
    for _ in range(repeat):
        for with_policies in (False, True):
            f = fleet(with_policies)
            c0 = time.process_time()
            res = f.run()
            cpu = time.process_time() - c0
            drone_s = sum(res.kpis[f"d{i}.flight_time_s"] for i in range(1, 5))
            out[with_policies].append(cpu / drone_s)
    return {k: statistics.median(v) for k, v in out.items()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--seconds", type=float, default=60.0)
    a = ap.parse_args()
    print(f"load average {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f}; "
          f"{a.seconds:g} s following after a {CLIMB_S:g} s climb; median of {a.repeat}")
    print(f"{'flight':<34} {'x real time':>12} {'x per CPU s':>12}")
    for kind, label in (("none", "no task, no policy"), ("oracle", "oracle 5 Hz + Follow"),
                        ("detector", "detector 5 Hz 320x240 + Follow")):
        wall, cpu, res = timed(kind, a.seconds, a.repeat)
        extra = (f"  track_error_p95_m {res.kpis['track_error_p95_m']:.2f}"
                 if kind != "none" else "")
        print(f"{label:<34} {wall:>12.0f} {cpu:>12.0f}{extra}")
    parts = where_time_goes(a.seconds)
    total = parts.pop("total (profiled)")
    print(f"detector flight, profiled: {total:.2f} s wall")
    for k, v in parts.items():
        print(f"  {k:<16} {v:6.2f} s  {100 * v / total:5.1f} %")
    rest = total - sum(parts.values())
    print(f"  {'the rest':<16} {rest:6.2f} s  {100 * rest / total:5.1f} %")
    cost = fleet_cost(a.repeat)
    print(f"fleet of 4, oracle 5 Hz each: {1e3 * cost[False]:.2f} ms CPU per drone-second "
          f"without policies, {1e3 * cost[True]:.2f} with SharedSearch "
          f"({100 * (cost[True] / cost[False] - 1):+.1f} %)")
    print(f"load average after {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
