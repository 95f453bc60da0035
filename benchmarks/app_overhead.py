"""CPU cost of the MAVLink front-end (pytest_flockai.app) against the same flight flown
by a Policy: the mission program of tests/apps (3 waypoints, return to launch) flown by
the app at ``--speed``, and the same waypoints flown by ``Mission(Waypoints, policies=
[a Policy doing nothing at the autopilot's period])`` on the drone's estimate. CPU seconds of this
process (the app's own process is not counted) per simulated second, best of ``--runs``.

    PYTHONPATH=$PWD python benchmarks/app_overhead.py --speed 20 --runs 3
"""

from __future__ import annotations

import argparse
import os
import sys
import time

import pytest_flockai as fa
from pytest_flockai.app.autopilot import PERIOD_S
from pytest_flockai.control.pilots import Waypoints

HERE = os.path.dirname(os.path.abspath(__file__))
APP = os.path.join(HERE, "..", "tests", "apps", "mavsdk_mission.py")


class Idle(fa.Policy):
    def decide(self, t, drone):
        pass


def policy_flight(drone):
    pts = [(0.0, 20.0, 10.0), (15.0, 20.0, 10.0), (15.0, 0.0, 8.0)]
    m = fa.Mission(drone, Waypoints(pts, 5.0), fly_on="estimate",
                   policies=[Idle(period_s=PERIOD_S)])
    c0 = time.process_time()
    res = m.run()
    return time.process_time() - c0, res.scenario["sim_time_s"]


def app_flight(drone, speed):
    c0 = time.process_time()
    r = fa.app.run([sys.executable, APP], drone, speed=speed, timeout_s=300)
    assert r.exit_code == 0, r.output
    return time.process_time() - c0, r.result.scenario["sim_time_s"], r.wall_s


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--speed", type=float, default=20.0)
    ap.add_argument("--runs", type=int, default=3)
    a = ap.parse_args()
    drone = fa.drone("dji-mavic-2-pro")
    pol = min(c / s for c, s in (policy_flight(drone) for _ in range(a.runs)))
    runs = [app_flight(drone, a.speed) for _ in range(a.runs)]
    app = min(c / s for c, s, _ in runs)
    print(f"policy flight: {pol * 1000:.1f} ms CPU per simulated s")
    print(f"app flight at {a.speed:g}x: {app * 1000:.1f} ms CPU per simulated s "
          f"(wall {min(w for *_, w in runs):.1f} s)")
    print(f"front-end overhead: {100 * (app / pol - 1):+.0f} %")


if __name__ == "__main__":
    main()
