"""Cameras: rendered frames and their ground truth, replay, dataset export."""

import math
import os
import subprocess
import sys

import cv2
import mujoco
import numpy as np
import pytest

import pytest_flockai as fa
from pytest_flockai import ConfigError
from pytest_flockai.airframe.mjspec import build_spec
from pytest_flockai.sensors import Camera, ReplayCamera, SensorSuite, export_dataset, render_views

CROWD = (60.0, 40.0, 50, 5.0)


@pytest.fixture(scope="module")
def flight():
    """A drone 30 m over a 50-person crowd, rolled 12 deg and yawed: one rendered frame."""
    world = fa.World.urban(seed=3, people=40, crowds=[CROWD])
    cam = Camera(320, 240, fov_deg=60, pitch_deg=-90, occlusion=False)
    spec = build_spec(fa.drone("dji-mavic-2-pro"), world, physics_dt=0.002)
    SensorSuite([cam]).add_to_spec(spec)
    m = spec.compile()
    d = mujoco.MjData(m)
    yaw, roll = 0.6, math.radians(12)
    q_yaw = np.array([math.cos(yaw / 2), 0, 0, math.sin(yaw / 2)])
    q_roll = np.array([math.cos(roll / 2), math.sin(roll / 2), 0, 0])
    q = np.zeros(4)
    mujoco.mju_mulQuat(q, q_yaw, q_roll)
    d.qpos[:3] = (CROWD[0], CROWD[1], 30.0)
    d.qpos[3:7] = q
    mujoco.mj_forward(m, d)
    suite = SensorSuite([cam])
    suite.bind(m, d, 0, world=world)
    frame = suite.read("camera", 12.5, d)
    return world, cam, m, d, frame, yaw


def _independent_projection(world, d, cam, yaw):
    """The test's own pinhole model: camera under the body, levelled, top of image = nose."""
    R = d.xmat[1].reshape(3, 3)
    c = d.xpos[1] + R @ cam.mount
    fwd = np.array([math.cos(yaw), math.sin(yaw), 0.0])      # image up, on the ground
    right = np.array([math.sin(yaw), -math.cos(yaw), 0.0])
    f = 120 / math.tan(math.radians(30))
    p = world.people + [0, 0, 0.85] - c
    depth = -p[:, 2]
    u = 160 + f * (p @ right) / depth
    v = 120 - f * (p @ fwd) / depth
    inside = (u >= 0) & (u < 320) & (v >= 0) & (v < 240)
    return np.flatnonzero(inside), np.column_stack([u, v])


def test_truth_count_matches_geometry(flight):
    world, cam, m, d, frame, yaw = flight
    truth = cam.last_truth
    idx, uv = _independent_projection(world, d, cam, yaw)
    assert truth.count == len(idx) >= 40          # the crowd is in view
    assert truth.indices.tolist() == idx.tolist()
    assert truth.pixels == pytest.approx(uv[idx], abs=1e-6)
    assert truth.t == 12.5 and cam.last_t == 12.5 and cam.frames == 1
    # the same truth without rendering
    assert cam.truth(12.5, d).indices.tolist() == idx.tolist()


def test_gimbal_levels_the_camera(flight):
    world, cam, m, d, frame, yaw = flight
    _, R = cam.pose(d)
    assert R[:, 2] == pytest.approx([0, 0, 1], abs=1e-12)             # straight down
    assert R[:, 1] == pytest.approx([math.cos(yaw), math.sin(yaw), 0], abs=1e-12)


def _matches(px, rgb):
    """A rendered pixel looks like the base colour under some light level (0.25..1.1)."""
    px = px.astype(float)
    base = np.asarray(rgb) * 255.0
    k = np.clip(px @ base / (base @ base), 0.25, 1.1)
    return np.linalg.norm(px - k * base) < 22.0


def test_frame_shows_the_figures_where_the_truth_says(flight):
    world, cam, m, d, frame, yaw = flight
    assert frame.shape == (240, 320, 3) and frame.dtype == np.uint8
    truth = cam.last_truth
    # the same view of the same city without its people (same seed: same buildings)
    bare = fa.World.urban(seed=3, people=0, crowds=[(60.0, 40.0, 0, 5.0)])
    assert np.array_equal(bare.buildings, world.buildings)
    cam_pos, _ = cam.pose(d)
    (empty_frame, empty_truth), = render_views(bare, [(*cam_pos, yaw)], cam)
    assert empty_truth.count == 0
    diff = np.abs(frame.astype(int) - empty_frame.astype(int)).sum(axis=2) > 30
    found = colour = 0
    for i, (u, v) in zip(truth.indices, truth.pixels):
        r, c = int(v), int(u)
        win = (slice(max(r - 3, 0), r + 4), slice(max(c - 3, 0), c + 4))
        if diff[win].any():
            found += 1
        pix = frame[win].reshape(-1, 3)
        if any(_matches(p, world.clothes[i]) or _matches(p, world.skin[i]) for p in pix):
            colour += 1
    n = truth.count
    assert found == n                              # every person in the truth is drawn there
    assert colour >= 0.9 * n                       # in its own clothes/skin colour
    # and figures are drawn only where people are (away from the image border)
    far = np.ones_like(diff)
    _, uv_all = _independent_projection(world, d, cam, yaw)
    for u, v in uv_all:
        r, c = int(round(v)), int(round(u))
        far[max(r - 8, 0):max(r + 9, 0), max(c - 8, 0):max(c + 9, 0)] = False
    far[:8, :] = far[-8:, :] = far[:, :8] = far[:, -8:] = False
    assert not (diff & far).any()


def test_frames_render_only_on_request_and_camera_code_needs_no_gl():
    code = ("import sys, numpy as np, mujoco, pytest_flockai as fa\n"
            "from pytest_flockai.sensors import Camera, GPS, SensorSuite\n"
            "from pytest_flockai.airframe.mjspec import build_spec\n"
            "w = fa.World.urban(seed=1, people=20)\n"
            "cam = Camera()\n"
            "spec = build_spec(fa.drone('dji-mavic-2-pro'), w, physics_dt=0.002)\n"
            "s = SensorSuite([GPS(), cam]); s.add_to_spec(spec)\n"
            "m = spec.compile(); d = mujoco.MjData(m); mujoco.mj_forward(m, d)\n"
            "s.bind(m, d, 0, world=w)\n"
            "[s.step(k * 0.01, d) for k in range(200)]\n"
            "cam.truth(0.0, d)\n"
            "from pytest_flockai.sensors import _gl\n"
            "assert _gl.backend() is None and cam.frames == 0\n"
            "assert 'mujoco.egl' not in sys.modules and 'mujoco.osmesa' not in sys.modules\n")
    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM")}
    subprocess.run([sys.executable, "-c", code], check=True, timeout=120, env=env)


def test_render_views_builds_training_data(tmp_path):
    w = fa.World.urban(seed=4, people=10, crowds=[(30.0, -30.0, 20, 3.0)])
    poses = [(30.0, -30.0, 25.0, 0.0), (30.0, -30.0, 40.0, 1.0), (0.0, 0.0, 60.0)]
    views = render_views(w, poses, dict(width=160, height=120))
    assert [f.shape for f, _ in views] == [(120, 160, 3)] * 3
    assert views[0][1].count >= 15
    df = export_dataset([(k, f, t) for k, (f, t) in enumerate(views)], tmp_path / "ds")
    assert list(df["count"]) == [t.count for _, t in views]
    assert sorted(p.name for p in (tmp_path / "ds").iterdir()) == [
        "annotations.json", "frame_00000.png", "frame_00001.png", "frame_00002.png", "truth.csv",
        "truth.json"]
    # the folder replays with its truth
    rc = ReplayCamera(tmp_path / "ds", rate_hz=1.0)
    rc.bind(None, None, np.random.default_rng(0))
    rc.read(0.0)                                       # the recording starts at the first read
    f = rc.read(1.2)
    assert np.array_equal(f, views[1][0])            # PNG is lossless
    assert rc.last_truth.count == views[1][1].count
    with pytest.raises(ConfigError, match="expected uint8"):
        export_dataset([(0, np.zeros((4, 4)), None)], tmp_path / "bad")
    with pytest.raises(ConfigError, match=r"poses\[0\]"):
        render_views(w, [(1, 2)])


def _write_images(folder, colours):
    folder.mkdir()
    for name, c in colours.items():
        img = np.zeros((24, 32, 3), np.uint8)
        img[:] = c
        cv2.imwrite(str(folder / name), cv2.cvtColor(img, cv2.COLOR_RGB2BGR))


def test_replay_folder_in_order_at_the_stated_rate(tmp_path):
    cols = {"img_02.png": (0, 0, 255), "img_00.png": (255, 0, 0), "img_01.png": (0, 255, 0)}
    _write_images(tmp_path / "seq", cols)
    rc = ReplayCamera(tmp_path / "seq", rate_hz=2.0, loop=True)
    rc.bind(None, None, np.random.default_rng(0))
    assert (rc.width, rc.height, rc.n_frames) == (32, 24, 3)
    seen = [tuple(rc.read(t)[0, 0]) for t in (0.0, 0.49, 0.5, 1.0, 1.49, 1.5, 2.0)]
    R, G, B = (255, 0, 0), (0, 255, 0), (0, 0, 255)
    assert seen == [R, R, G, B, B, R, G]
    assert rc.frames == 7 and rc.last_t == 2.0
    once = ReplayCamera(tmp_path / "seq", rate_hz=2.0, loop=False)
    once.bind(None, None, np.random.default_rng(0))
    # the recording starts at the first read (a task's first tick, after take-off)
    assert [tuple(once.read(t)[0, 0]) for t in (1.2, 1.5, 2.0)] == [R, G, B]
    assert once.read(2.5) is None and once.ended


def test_replay_video(tmp_path):
    p = str(tmp_path / "clip.avi")
    vw = cv2.VideoWriter(p, cv2.VideoWriter_fourcc(*"MJPG"), 10.0, (32, 24))
    colours = [(255, 0, 0), (0, 255, 0), (0, 0, 255)]
    for c in colours:
        img = np.zeros((24, 32, 3), np.uint8)
        img[:] = c
        vw.write(cv2.cvtColor(img, cv2.COLOR_RGB2BGR))
    vw.release()
    rc = ReplayCamera(p, rate_hz=1.0)
    rc.bind(None, None, np.random.default_rng(0))
    got = [rc.read(t)[12, 16].astype(int) for t in (0.0, 1.0, 2.0, 3.0, 4.0)]
    want = [colours[k % 3] for k in range(5)]
    assert all(np.abs(g - w).max() < 40 for g, w in zip(got, want))


def test_bad_camera_inputs(tmp_path):
    with pytest.raises(ConfigError, match="width = 0"):
        Camera(width=0)
    with pytest.raises(ConfigError, match="height = -5"):
        Camera(height=-5)
    with pytest.raises(ConfigError, match="fov_deg"):
        Camera(fov_deg=0)
    with pytest.raises(ConfigError, match="pitch_deg"):
        Camera(pitch_deg=-120)
    with pytest.raises(ConfigError, match=r"missing.*no such folder or video"):
        ReplayCamera(tmp_path / "missing")
    (tmp_path / "empty").mkdir()
    with pytest.raises(ConfigError, match="empty.*holds no images"):
        ReplayCamera(tmp_path / "empty")
    junk = tmp_path / "junk.mp4"
    junk.write_bytes(b"not a video at all")
    with pytest.raises(ConfigError, match="junk.mp4.*not a readable video"):
        ReplayCamera(junk)
    with pytest.raises(ConfigError, match="rate_hz"):
        ReplayCamera(tmp_path / "empty", rate_hz=-1)


def test_camera_from_blueprint():
    d = fa.drone("dji-mavic-2-pro")
    cam = Camera.from_blueprint(d)
    assert (cam.width, cam.height, cam.fov_deg, cam.pitch_deg) == (
        d.camera.width, d.camera.height, d.camera.fov_deg, d.camera.pitch_deg)


def test_no_working_gl_gives_a_clear_error_only_when_a_camera_is_used(tmp_path):
    """With a GL backend that cannot start (OSMesa is not installed on the CI
    image; skipped where it is), camera-less flights still fly and the first
    camera use raises FlockAIError saying what to install."""
    import ctypes.util
    import subprocess
    import sys
    if ctypes.util.find_library("OSMesa"):
        pytest.skip("OSMesa is installed here: it would work")
    script = tmp_path / "nogl.py"
    script.write_text(
        "import pytest_flockai as fa\n"
        "r = fa.Mission(fa.drone('crazyflie-2-1'), fa.pilots.Hover(1.0, 0.5)).run()\n"
        "print('camera-less flight', r.end_reason)\n"
        "task = fa.Task(fa.ml.PythonModel(lambda f: 0.0, macs=1), period_s=1.0)\n"
        "try:\n"
        "    fa.Mission(fa.drone('dji-mavic-2-pro'), fa.pilots.Hover(5.0, 3.0), tasks=[task]).run()\n"
        "except fa.FlockAIError as e:\n"
        "    print('ERROR', e)\n")
    env = dict(os.environ, MUJOCO_GL="osmesa")
    out = subprocess.run([sys.executable, str(script)], env=env, capture_output=True, text=True,
                         timeout=120)
    assert "camera-less flight landed" in out.stdout, out.stderr
    assert "ERROR the camera cannot render" in out.stdout
    assert "osmesa" in out.stdout.lower() and "install" in out.stdout.lower()
