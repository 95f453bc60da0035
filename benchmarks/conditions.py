"""Imaging conditions: per-frame cost, and scenario 1-B's real-time factor with them.

    MUJOCO_GL=egl python benchmarks/conditions.py

Prints the cost of ``fa.Conditions`` (light, haze, blur, noise; rolling shutter;
each weather) on one 320x240 frame, the render cost of a frame with and without
the sun's shadows, and scenario 1-B (the shipped CNN on a Raspberry Pi 4) over the paper's
city, short survey, with the CNN every 5 s and at 1 Hz, with an ideal camera
and with every condition on (median of 3).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import mujoco
import numpy as np

import pytest_flockai as fa
from pytest_flockai.sensors.camera import FrameRenderer
from pytest_flockai.sensors.conditions import apply
from pytest_flockai.world.truth import gimbal_pose

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "example_tests"))
import scenarios  # noqa: E402

ALL = fa.Conditions(exposure_s=1 / 250, sun_elevation_deg=20, visibility_m=800, gimbal_jitter_dps=2.0)


def frame_cost(cond=ALL, n: int = 200, skew=(0.0, 0.0)) -> float:
    f = np.random.default_rng(0).integers(0, 255, (240, 320, 3), dtype=np.uint8)
    d = np.full((240, 320), 30.0, np.float32)
    rng = np.random.default_rng(0)
    apply(f, cond, rng, distance=d, blur=(1.5, 0.3), skew=skew)     # warm (imports, caches)
    t = time.perf_counter()
    for _ in range(n):
        apply(f, cond, rng, distance=d, blur=(1.5, 0.3), skew=skew)
    return (time.perf_counter() - t) / n


def render_cost(world, n: int = 20) -> dict:
    """ms per 320x240 frame of ``world``: ideal, under a given sun, with its shadows."""
    spec = mujoco.MjSpec()
    world.add_to_spec(spec)
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    r = FrameRenderer(model, 320, 240)
    pos, mat = gimbal_pose((20.0, 10.0, 30.0), 0.3, -90.0)
    out = {}
    try:
        for label, kw in (("ideal", {}), ("sun direction", {"sun_dir": (0.8, 0.3, -0.5)}),
                          ("sun and shadows", {"sun_dir": (0.8, 0.3, -0.5), "shadows": True})):
            r.render(data, pos, mat, 51.0, **kw)
            t = time.perf_counter()
            for _ in range(n):
                r.render(data, pos, mat, 51.0, **kw)
            out[label] = 1e3 * (time.perf_counter() - t) / n
    finally:
        r.close()
    return out


def main() -> int:
    print(f"conditions on one 320x240 frame: {1e3 * frame_cost():.2f} ms")
    print(f"  + rolling shutter (3 px skew): "
          f"{1e3 * frame_cost(fa.Conditions(readout_s=0.03), skew=(3.0, 0.0)):.2f} ms (alone)")
    for w in ("rain", "snow", "spatter"):
        c = fa.Conditions(weather=w, severity=3, noise=False)
        print(f"  weather {w:8s} severity 3: {1e3 * frame_cost(c, n=50):.2f} ms (alone)")
    for label, ms in render_cost(scenarios.detection_world()).items():
        print(f"render, detection city, {label:16s}: {ms:6.2f} ms")
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
