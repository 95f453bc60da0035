"""Imaging conditions: per-frame cost, and scenario 1-B's real-time factor with them.

    MUJOCO_GL=egl python benchmarks/conditions.py

Prints the cost of ``fa.Conditions`` (light, haze, blur, noise) on one 320x240
frame, and scenario 1-B (the shipped CNN on a Raspberry Pi 4) over the paper's
city, short survey, with the CNN every 5 s and at 1 Hz, with an ideal camera
and with every condition on (median of 3).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

import pytest_flockai as fa
from pytest_flockai.sensors.conditions import apply

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "example_tests"))
import scenarios  # noqa: E402

ALL = fa.Conditions(exposure_s=1 / 250, sun_elevation_deg=20, visibility_m=800, gimbal_jitter_dps=2.0)


def frame_cost(n: int = 200) -> float:
    f = np.random.default_rng(0).integers(0, 255, (240, 320, 3), dtype=np.uint8)
    d = np.full((240, 320), 30.0, np.float32)
    rng = np.random.default_rng(0)
    t = time.perf_counter()
    for _ in range(n):
        apply(f, ALL, rng, distance=d, blur=(1.5, 0.3))
    return (time.perf_counter() - t) / n


def main() -> int:
    print(f"conditions on one 320x240 frame: {1e3 * frame_cost():.2f} ms")
    cnn, w = scenarios.cnn(), scenarios.world()

    def fly(cond, period):
        task = fa.Task(cnn, period_s=period, execution="onboard", device="raspberry-pi-4", name="cnn")
        return fa.Mission(fa.drone("dji-mavic-2-pro"), scenarios.survey(), world=w, tasks=[task],
                          seed=0, conditions=cond).run()
    fly(None, 5.0)
    for label, cond, period in (("1-B, CNN every 5 s, ideal camera", None, 5.0),
                                ("1-B, CNN every 5 s, all conditions", ALL, 5.0),
                                ("1-B, CNN and camera at 1 Hz, ideal", None, 1.0),
                                ("1-B, CNN and camera at 1 Hz, all conditions", ALL, 1.0)):
        rtf = sorted(fly(cond, period).rtf for _ in range(3))[1]
        print(f"{label:46s} {rtf:6.0f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
