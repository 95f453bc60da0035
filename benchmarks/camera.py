"""Camera and world speed: rendered frames/s and mj_step cost, urban vs empty world.

    MUJOCO_GL=egl python benchmarks/camera.py [--frames 60] [--steps 20000]

Prints frames/s of the gimballed camera over the urban world (200 x 200 m,
100 scattered people + a crowd of 50) at 160x120, 320x240 and 640x480, and
the wall time of one mj_step of the Mavic 2 Pro model in the empty and the
urban world (drone hovering at 30 m, so only the broad phase runs; and resting
on the ground, with contacts).
"""

from __future__ import annotations

import argparse
import time

import mujoco
import numpy as np

import pytest_flockai as fa
from pytest_flockai.airframe.mjspec import build_spec
from pytest_flockai.sensors import Camera


def model_with(world, camera=None):
    d = fa.drone("dji-mavic-2-pro")
    spec = build_spec(d, world, physics_dt=1.0 / d.sim.physics_hz)
    if camera is not None:
        camera.add_to_spec(spec)
    m = spec.compile()
    return d, m, mujoco.MjData(m)


def step_cost(world, steps, z):
    d, m, data = model_with(world)
    data.qpos[:3] = (0.0, 0.0, z)
    hover = d.mass_kg * 9.81 / m.nu
    data.ctrl[:] = hover if z > 1 else 0.0
    data.act[:] = data.ctrl
    mujoco.mj_forward(m, data)
    best = np.inf
    for _ in range(3):
        q0, v0 = data.qpos.copy(), data.qvel.copy()
        t = time.perf_counter()
        mujoco.mj_step(m, data, steps)
        best = min(best, (time.perf_counter() - t) / steps)
        data.qpos[:], data.qvel[:] = q0, v0
    return best, m.ngeom


def fps(world, width, height, frames):
    cam = Camera(width, height, world=world)
    _, m, data = model_with(world, cam)
    data.qpos[:3] = (60.0, 40.0, 30.0)
    mujoco.mj_forward(m, data)
    cam.bind(m, data, np.random.default_rng(0))
    cam.read(0.0, data)                       # GL context, textures: not timed
    t = time.perf_counter()
    for k in range(frames):
        data.qpos[3:7] = (np.cos(0.05 * k), 0, 0, np.sin(0.05 * k))   # turn: new views
        mujoco.mj_kinematics(m, data)
        cam.read(k, data)
    dt = time.perf_counter() - t
    t = time.perf_counter()
    for k in range(frames):
        cam.truth(k, data)
    dt_truth = time.perf_counter() - t
    cam.close()
    return frames / dt, dt_truth / frames


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--frames", type=int, default=60)
    ap.add_argument("--steps", type=int, default=20000)
    a = ap.parse_args()
    urban = fa.World.urban(seed=0, size=(200.0, 200.0), people=100, crowds=[(60.0, 40.0, 50, 5.0)],
                           max_building_height=35.0)
    print(f"urban world: {len(urban.buildings)} buildings, {len(urban.people)} people")
    print("\nrendered camera (gimballed, urban world, crowd in view)")
    print(f"{'size':>10} {'frames/s':>10} {'ms/frame':>10} {'truth ms':>10}")
    from pytest_flockai.sensors import _gl
    for w, h in ((160, 120), (320, 240), (640, 480)):
        f, tt = fps(urban, w, h, a.frames)
        print(f"{w}x{h:<6} {f:10.1f} {1000 / f:10.2f} {1000 * tt:10.3f}")
    print(f"GL backend: {_gl.backend()}")
    print(f"\nmj_step cost (Mavic 2 Pro, {a.steps} steps, best of 3)")
    print(f"{'world':>8} {'state':>10} {'ngeom':>6} {'us/step':>9}")
    for name, world in (("empty", fa.World.empty()), ("urban", urban)):
        for state, z in (("hover", 30.0), ("ground", 0.2)):
            c, ng = step_cost(world, a.steps, z)
            print(f"{name:>8} {state:>10} {ng:6d} {1e6 * c:9.2f}")
    cars = fa.World.urban(seed=0, size=(200.0, 200.0), people=100, crowds=[(60.0, 40.0, 50, 5.0)],
                          max_building_height=35.0, vehicles=60)
    print("\nmission RTF, Mavic 2 Pro ZigZag over the urban world (+60 cars), 300 s simulated "
          "(median of 5, interleaved)")
    print(f"{'camera':>34} {'RTF':>8} {'wall s':>8} {'frames':>8}")
    runs = (("none", None, True), ("1 Hz, 320x240, no object truth", 1.0, False),
            ("1 Hz, 320x240, object truth", 1.0, True))
    rtfs: dict = {label: [] for label, _, _ in runs}
    walls: dict = {label: [] for label, _, _ in runs}
    frames = {}
    for _ in range(5):
        for label, period, objects in runs:
            r = mission_with_camera(cars, period, objects)
            rtfs[label].append(r.rtf)
            walls[label].append(r.wall_time_s)
            frames[label] = int(r.kpis.get("inference_count", 0))
    for label, _, _ in runs:
        print(f"{label:>34} {sorted(rtfs[label])[2]:8.0f} {sorted(walls[label])[2]:8.2f} "
              f"{frames[label]:8d}")
    w0 = sorted(walls["1 Hz, 320x240, no object truth"])[2]
    w1 = sorted(walls["1 Hz, 320x240, object truth"])[2]
    print(f"object truth adds {100 * (w1 / w0 - 1):+.1f} % wall time to the 1 Hz camera mission")


def mission_with_camera(world, period, objects=True):
    """A survey whose only task reads the camera every ``period`` s (a no-op model);
    ``objects``: whether the camera computes per-object truth."""
    tasks = []
    blueprint_camera = Camera.from_blueprint
    if not objects:
        Camera.from_blueprint = classmethod(lambda cls, c, **kw: blueprint_camera(c, objects=False, **kw))
    if period is not None:
        tasks = [fa.Task(fa.ml.PythonModel(lambda frame: 0.0, macs=1, name="noop"), period_s=period)]
    pilot = fa.pilots.ZigZag(area=((-90, -90), (90, 90)), altitude=40, spacing=30, speed=8)
    try:
        return fa.Mission(fa.drone("dji-mavic-2-pro"), pilot, world=world, tasks=tasks,
                          until=300.0).run()
    finally:
        Camera.from_blueprint = blueprint_camera


if __name__ == "__main__":
    main()
