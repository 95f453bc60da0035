"""Golden scenarios: short flights that exercise every part of the flight loop
(stages, wind, sensors and the estimator, energy, radio, tasks on board and
remote, camera truth, battery reserve, time limits).

``python tests/golden/scenarios.py`` records their KPIs, end reasons and event
counts into ``tests/golden/golden.json``; ``tests/mission/test_golden.py`` flies them again
and compares. The file was recorded before the flight loop was reshaped into
clocked components, so it proves that reshaping did not move
behaviour. Re-record only for an intended change of behaviour, and say why in
the commit.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

import pytest_flockai as fa

HERE = Path(__file__).resolve().parent
GOLDEN = HERE / "golden.json"


def _bright(frame):
    return float((np.asarray(frame).mean(axis=2) > 200).sum() // 50)


def _world():
    return fa.World.urban(seed=3, size=(120.0, 120.0), people=30, crowds=[(30.0, 20.0, 20, 4.0)],
                          max_building_height=15.0)


def scenarios() -> dict:
    """name -> a function returning a fresh Mission."""
    zz = dict(area=((-40, -40), (40, 40)), altitude=25, spacing=40, speed=8)
    model = lambda: fa.ml.PythonModel(_bright, macs=5.26e8, name="cnn")   # noqa: E731
    return {
        "hover": lambda: fa.Mission(fa.drone("dji-mavic-2-pro"), fa.pilots.Hover(10, 15), seed=0),
        "zigzag-wind": lambda: fa.Mission(
            fa.drone("dji-mavic-2-pro"), fa.pilots.ZigZag(**zz),
            wind=fa.Wind(mean=(4.0, -2.0, 0.0), gust_std=1.5), seed=3),
        "crazyflie-waypoints": lambda: fa.Mission(
            fa.drone("crazyflie-2-1"), fa.pilots.Waypoints([(1, 0, 1), (1, 1, 1.5), (0, 1, 1)], speed=1.0),
            seed=1),
        "hexa-orbit-timed": lambda: fa.Mission(
            fa.drone("generic-hexa-680"), fa.pilots.Orbit(center=(10, 0), radius=10, altitude=15, speed=4),
            until=40.0, seed=2),
        "estimate-sensors": lambda: fa.Mission(
            fa.drone("dji-mavic-2-pro"), fa.pilots.Waypoints([(20, 0, 10), (20, 20, 10)], speed=5),
            sensors=[fa.sensors.BatterySensor(), fa.sensors.IMU()], fly_on="estimate", seed=4),
        "reserve": lambda: fa.Mission(
            # the Mavic's cell resistance (3850 mAh pack): a short flight, not a weak battery
            fa.drone("dji-mavic-2-pro", battery_mah=300, internal_resistance_mohm=7.8),
            fa.pilots.Waypoints([(30, 0, 10), (30, 30, 10)], speed=5, loop=True),
            until="battery_reserve", seed=5),
        "depleted": lambda: fa.Mission(
            fa.drone("crazyflie-2-1", battery_mah=20, internal_resistance_mohm=120.0),  # the 250 mAh cell's
            fa.pilots.Hover(1.0), until="battery_depleted"),
        "onboard-task": lambda: fa.Mission(
            fa.drone("dji-mavic-2-pro"), fa.pilots.ZigZag(**zz), world=_world(),
            tasks=[fa.Task(model(), period_s=2.0, execution="onboard", device="raspberry-pi-4")], seed=0),
        "remote-task": lambda: fa.Mission(
            fa.drone("dji-mavic-2-pro"), fa.pilots.ZigZag(**zz), world=_world(),
            tasks=[fa.Task(model(), period_s=2.0, execution="remote", link="sik-915")], seed=0),
    }


def summary(result) -> dict:
    kinds: dict = {}
    for e in result.events:
        kinds[e["kind"]] = kinds.get(e["kind"], 0) + 1
    return {"end_reason": result.end_reason, "kpis": result.kpis, "events": kinds,
            "telemetry_rows": int(len(result.telemetry)),
            "breakdown": result.energy_breakdown}


def fly(name: str) -> dict:
    return summary(scenarios()[name]().run())


def main(argv) -> int:
    out = {name: fly(name) for name in scenarios()}
    GOLDEN.write_text(json.dumps(out, indent=1, sort_keys=True, default=float) + "\n")
    print(f"recorded {len(out)} scenarios into {GOLDEN}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
