"""Motion blur: sub-pixel kernels are applied, one distance rule whatever the haze,
the length per frame in telemetry, events and the exported truth; conditions on
replayed frames where they are physical; bad Conditions values refused."""

import json
import math

import cv2
import numpy as np
import pytest

import pytest_flockai as fa
from pytest_flockai.sensors import export_dataset, render_views
from pytest_flockai.sensors.conditions import apply

F = 0.5 * 240 / math.tan(math.radians(51.0) / 2)          # the Mavic camera's focal length, px


def test_a_blur_of_0_7_px_changes_the_frame_at_the_edges_only():
    frame = np.full((40, 40, 3), 40, np.uint8)
    frame[:, 20:] = 220                                       # a vertical edge
    cond = fa.Conditions(noise=False, auto_exposure=False)
    rng = np.random.default_rng(0)
    sharp = apply(frame, cond, rng)
    blurred = apply(frame, cond, rng, blur=(0.7, 0.0))
    changed = np.flatnonzero(np.abs(blurred.astype(int) - sharp.astype(int)).sum(axis=(0, 2)))
    assert set(changed) <= {19, 20} and len(changed) >= 1     # the smear crosses the edge
    assert np.array_equal(apply(frame, cond, rng, blur=(0.0, 0.7))[:, :18], sharp[:, :18])


def _fly_blur(visibility_m):
    world = fa.World.urban(seed=5, size=(100.0, 100.0), people=20, vehicles=5,
                           max_building_height=25.0)
    cam = fa.sensors.Camera(fov_deg=51.0, name="eye", width=160, height=120, conditions=
                            fa.Conditions(exposure_s=0.02, noise=False, visibility_m=visibility_m))
    d = fa.drone("dji-mavic-2-pro")
    d.add_sensor(cam)
    seen = []

    def model(frame):
        seen.append(math.hypot(*cam.last_truth.blur_px))
        return 0.0
    pilot = fa.pilots.Waypoints([(0.0, 0.0, 30.0), (40.0, 0.0, 30.0)], speed=10.0)
    r = fa.Mission(d, pilot, world=world, tasks=[fa.Task(fa.ml.PythonModel(model, macs=1),
                                                         sensor="eye", period_s=0.5)]).run()
    return seen, r


def test_the_blur_length_is_the_same_with_and_without_haze_and_is_recorded_per_frame():
    clear, r = _fly_blur(math.inf)
    hazy, _ = _fly_blur(1e6)
    assert len(clear) >= 8 and max(clear) > 0.5              # a pass at 10 m/s, 1/50 s
    assert hazy == clear
    inf = [e for e in r.events if e.get("kind") == "inference"]
    assert [e["blur_px"] for e in inf] == pytest.approx(clear)
    tel = r.telemetry["blur_px"].dropna()
    assert len(tel) > 0 and tel.max() == pytest.approx(max(clear))


def test_the_exported_truth_carries_each_frames_blur(tmp_path):
    w = fa.World.scene(people=[(0.0, 0.0)], size=(60.0, 60.0))
    cond = fa.Conditions(exposure_s=1 / 30, noise=False)
    views = render_views(w, [(0.0, 0.0, 20.0, 0.0)], {"fov_deg": 51.0, "width": 160, "height": 120},
                         conditions=cond, velocity=(8.0, 0.0, 0.0))
    export_dataset([(0.0, f, t) for f, t in views], tmp_path)
    length = math.hypot(*views[0][1].blur_px)
    assert length == pytest.approx(8.0 / 30 * (0.5 * 120 / math.tan(math.radians(25.5))) / 20.0,
                                   rel=0.02)
    truth = json.loads((tmp_path / "truth.json").read_text())["frames"][0]
    coco = json.loads((tmp_path / "annotations.json").read_text())["images"][0]
    assert math.hypot(*truth["blur_px"]) == pytest.approx(length, abs=1e-3)
    assert coco["blur_px"] == pytest.approx(length, abs=1e-3)
    replay = fa.sensors.ReplayCamera(tmp_path)
    assert math.hypot(*replay._truth[0].blur_px) == pytest.approx(length, abs=1e-3)


def test_a_replayed_frame_takes_the_flights_blur_noise_and_light(tmp_path):
    img = np.full((480, 640, 3), 60, np.uint8)
    img[::8, ::8] = 230                                      # 1 px dots: smeared along any motion
    for i in range(3):
        cv2.imwrite(str(tmp_path / f"f{i}.png"), img)
    cam = fa.sensors.ReplayCamera(tmp_path, rate_hz=2.0, name="eye", conditions=fa.Conditions(
        exposure_s=0.02, sun_elevation_deg=20.0))
    d = fa.drone("dji-mavic-2-pro")
    d.add_sensor(cam)
    seen = []

    def model(frame):
        seen.append((float(frame[:, :, 0].std()), math.hypot(*cam.last_blur_px)))
        return 0.0
    pilot = fa.pilots.Waypoints([(0.0, 0.0, 30.0), (120.0, 0.0, 30.0)], speed=10.0)
    fa.Mission(d, pilot, tasks=[fa.Task(fa.ml.PythonModel(model, macs=1), sensor="eye",
                                        period_s=0.5)]).run()
    f = 0.5 * 480 / math.tan(math.radians(51.0 / 2))
    fast = [s for s, b in seen if b > 0.9 * 10.0 * 0.02 * f / 30.0]      # cruising at 10 m/s
    slow = [s for s, b in seen if b < 0.3]
    assert len(fast) >= 5 and slow
    assert max(fast) < 0.6 * min(slow)                      # the stripes smeared by 3+ px
    with pytest.raises(fa.ConfigError, match="haze needs each pixel's distance"):
        fa.sensors.ReplayCamera(tmp_path, conditions=fa.Conditions(visibility_m=500.0))
    with pytest.raises(fa.ConfigError, match="cannot be lit again"):
        fa.sensors.ReplayCamera(tmp_path, conditions=fa.Conditions(shadows=True))


@pytest.mark.parametrize("kw", [dict(visibility_m="fog"), dict(visibility_m=None),
                                dict(visibility_m=[300]), dict(exposure_s="fast"),
                                dict(auto_exposure="yes"), dict(noise=1),
                                dict(sun_elevation_deg=None), dict(max_gain="x")])
def test_conditions_of_the_wrong_type_are_a_config_error_naming_the_field(kw):
    (field, value), = kw.items()
    with pytest.raises(fa.ConfigError, match=f"{field} = {value!r}".replace("[", r"\[")):
        fa.Conditions(**kw)
