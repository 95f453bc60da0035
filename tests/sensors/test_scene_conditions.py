"""Figures that look the part (articulated people in
poses, cars with glass and tyres), the sun's direction and its shadows, a
rolling shutter, and weather corruptions from albumentations."""

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import find, settings
from hypothesis.errors import NoSuchExample

import pytest_flockai as fa
from pytest_flockai import strategies as fst
from pytest_flockai.errors import ConfigError
from pytest_flockai.world import figures
from pytest_flockai.world.truth import project

W, H, FOV = 320, 240, 60.0
F = 0.5 * H / math.tan(math.radians(FOV) / 2)


def _ground_uv(views, x, y):
    pos, mat = views.poses[0]
    uv, _ = project([(x, y, 0.0)], pos, mat, FOV, W, H)
    return uv[0]


def _patch(img, uv, r=3):
    u, v = int(round(uv[0])), int(round(uv[1]))
    return float(img[v - r:v + r + 1, u - r:u + r + 1].astype(float).mean())


# -- figures ------------------------------------------------------------------------
def test_poses_are_drawn_from_their_own_stream_and_move_nothing_else():
    a = fa.World.urban(seed=3, people=60, vehicles=10, figures="articulated")
    b = fa.World.urban(seed=3, people=60, vehicles=10, figures="simple")
    np.testing.assert_array_equal(a.people, b.people)          # positions did not move
    np.testing.assert_array_equal(a.vehicles, b.vehicles)
    np.testing.assert_array_equal(a.clothes_idx, b.clothes_idx)
    np.testing.assert_array_equal(a.poses, fa.World.urban(seed=3, people=60, vehicles=10).poses)
    assert not np.array_equal(a.poses, fa.World.urban(seed=4, people=60).poses[:60])
    yaw, scale = a.poses[:, 0], a.poses[:, 1]
    assert yaw.std() > 1.0 and 0.85 <= scale.min() and scale.max() <= 1.15
    assert scale.std() == pytest.approx(figures.STATURE_SD, abs=0.02)
    assert len(np.unique(a.trousers_idx)) >= 4


def test_a_waving_figure_reaches_above_its_head_and_a_walking_one_strides():
    standing = figures.person([0, 1, 0, 0, 0.08, 0, 0.08])
    waving = figures.person([0, 1, 0, 0, 0.08, 0.2, 2.6])
    walking = figures.person([0, 1, 0.35, -0.35, 0.08, 0.35, 0.08])
    top = {k: max(p[0][:, 2].max() for p in v.values())
           for k, v in (("standing", standing), ("waving", waving))}
    assert top["standing"] == pytest.approx(figures.STATURE, abs=0.01)
    assert top["waving"] > figures.STATURE + 0.2                # the hand above the head
    reach = {k: np.ptp(v["legs"][0][:, 0]) for k, v in (("standing", standing), ("walking", walking))}
    assert reach["walking"] > reach["standing"] + 0.3           # the feet apart along x
    assert min(p[0][:, 2].min() for p in walking.values()) >= -1e-9     # nothing under ground


def test_articulated_figure_boxes_are_tight_on_the_rendered_pixels():
    """Figures in every pose, seen from 12 m: each object's truth box against the
    bounding box of the pixels that differ from the empty scene (within 1 px)."""
    people = [(-4.0, 0.0), (0.0, 0.0), (4.0, 0.0), (0.0, -4.0)]
    poses = [[0.0, 1.0, 0.0, 0.0, 0.08, 0.0, 0.08], [0.7, 1.1, 0.35, -0.35, 0.08, 0.35, 0.08],
             [2.0, 0.9, 0.0, 0.0, 0.08, 0.2, 2.6], [4.0, 1.0, 0.0, 1.45, 0.1, 0.0, 0.08]]
    camera = {"fov_deg": FOV, "width": W, "height": H, "pitch_deg": -60.0}
    pose = [(0.0, -12.0, 12.0, math.pi / 2)]
    full = fa.sensors.render_views(fa.World.scene(people=people, poses=poses, figures="articulated"), pose, camera)
    empty = fa.sensors.render_views(fa.World.scene(), pose, camera)[0][0]
    frame, truth = full[0]
    assert len(truth.objects) == 4
    for i in range(4):                     # one figure at a time: its own pixels
        alone = fa.sensors.render_views(
            fa.World.scene(people=[people[i]], poses=[poses[i]], figures="articulated"), pose, camera)[0][0]
        ys, xs = np.nonzero(np.abs(alone.astype(int) - empty.astype(int)).sum(axis=2) > 12)
        box = truth.objects.boxes[list(truth.objects.ids).index(i)]
        assert xs.min() >= box[0] - 1 and xs.max() + 1 <= box[2] + 1
        assert ys.min() >= box[1] - 1 and ys.max() + 1 <= box[3] + 1
        assert xs.min() <= box[0] + 1.5 and xs.max() + 1 >= box[2] - 1.5      # tight
        assert ys.min() <= box[1] + 1.5 and ys.max() + 1 >= box[3] - 1.5


def test_a_car_has_glass_and_tyres_and_keeps_the_golf_size():
    car = figures.CAR
    v = np.vstack([m[0] for m in car.values()])
    assert np.ptp(v[:, 0]) == pytest.approx(4.3, abs=0.01)
    assert np.ptp(v[:, 1]) == pytest.approx(1.8, abs=0.01)
    assert v[:, 2].max() == pytest.approx(1.46, abs=0.01) and v[:, 2].min() == pytest.approx(0)
    glass = car["glass"][0]
    assert glass[:, 2].min() >= 0.9 and np.ptp(glass[:, 0]) > 2.0   # the glasshouse band
    world = fa.World.scene(vehicles=[(0.0, 0.0, 0.0)], figures="articulated")   # white, east
    cam = {"fov_deg": FOV, "width": W, "height": H, "pitch_deg": -20.0}
    views = fa.sensors.ViewSet(world, [(10.0, 0.0, 4.0, math.pi)], cam)   # ahead, looking west
    frame = views.ideal()[0][0]
    pos, mat = views.poses[0]
    (wind, hood), _ = project([(0.70, 0.0, 1.17), (1.7, 0.0, 0.95)],
                                     pos, mat, FOV, W, H)
    assert _patch(frame, wind, 2) < 0.4 * _patch(frame, hood, 2)     # windscreen vs bonnet
    side = fa.sensors.ViewSet(world, [(0.0, -9.0, 1.0, math.pi / 2)],
                              {**cam, "pitch_deg": -5.0})             # from the side, low
    pos, mat = side.poses[0]
    (tyre, door), _ = project([(1.32, -0.9, 0.3), (0.0, -0.9, 0.6)], pos, mat, FOV, W, H)
    img = side.ideal()[0][0]
    assert _patch(img, tyre, 1) < 0.3 * _patch(img, door, 1)


def test_bad_figures_and_poses_are_refused():
    with pytest.raises(ConfigError, match="figures = 'capsule'"):
        fa.World.urban(figures="capsule")
    with pytest.raises(ConfigError, match="poses has 1 rows; expected one per person"):
        fa.World.scene(people=[(0, 0), (1, 1)], poses=[[0, 1, 0, 0, 0, 0, 0]])


# -- the sun ------------------------------------------------------------------------
def _tower_views():
    world = fa.World.scene(buildings=[(0.0, 0.0, 3.0, 3.0, 10.0)], size=(80.0, 80.0))
    return fa.sensors.ViewSet(world, [(0.0, 0.0, 60.0, 0.0)],
                              {"fov_deg": FOV, "width": W, "height": H})


@pytest.fixture(scope="module")
def tower():
    return _tower_views()


def test_the_shadow_falls_away_from_the_sun_with_the_length_of_h_over_tan_elevation(tower):
    """A 10 m tower, the sun in the west at 45 degrees: its shadow lies east of the
    tower and is 10 m long: dark at 3-12 m from the east wall, lit beyond and west."""
    c = fa.Conditions(sun_azimuth_deg=270.0, sun_elevation_deg=45.0, shadows=True, noise=False,
                      auto_exposure=False)
    img = tower.under(c)[0][0]
    east_in = _patch(img, _ground_uv(tower, 3.0 + 6.0, 0.0))       # 6 m past the east wall
    east_out = _patch(img, _ground_uv(tower, 3.0 + 14.0, 0.0))     # past the 10 m shadow
    west = _patch(img, _ground_uv(tower, -3.0 - 6.0, 0.0))
    assert east_in < 0.8 * east_out and east_in < 0.8 * west
    assert east_out == pytest.approx(west, rel=0.05)
    no_shadow = tower.under(dataclasses.replace(c, shadows=False))[0][0]
    assert _patch(no_shadow, _ground_uv(tower, 9.0, 0.0)) == pytest.approx(
        _patch(no_shadow, _ground_uv(tower, -9.0, 0.0)), rel=0.05)
    # the edge of the shadow: between 8 and 12 m from the wall for a 10 m long one
    profile = [_patch(img, _ground_uv(tower, 3.0 + d, 0.0), r=1) for d in np.arange(4, 16, 0.5)]
    edge = 4 + 0.5 * int(np.argmax(np.diff(profile)))
    assert 8.0 <= edge <= 12.0


def test_a_low_sun_casts_longer_shadows_and_turns_with_its_azimuth(tower):
    base = dict(shadows=True, noise=False, auto_exposure=False)
    low = tower.under(fa.Conditions(sun_azimuth_deg=270.0, sun_elevation_deg=30.0, **base))[0][0]
    north = tower.under(fa.Conditions(sun_azimuth_deg=0.0, sun_elevation_deg=45.0, **base))[0][0]
    lit = _patch(low, _ground_uv(tower, 25.0, 0.0))
    assert _patch(low, _ground_uv(tower, 3.0 + 14.0, 0.0)) < 0.8 * lit   # 17 m < 10/tan 30
    assert _patch(north, _ground_uv(tower, 0.0, -9.0)) < 0.8 * _patch(north, _ground_uv(tower, 0.0, 9.0))


# -- rolling shutter ------------------------------------------------------------------
def test_a_rolling_shutter_skews_a_straight_edge_by_speed_times_readout():
    """A building's long edge across the image, the camera moving at 12 m/s across it
    from 30 m, rows read over 30 ms: the edge's column moves by v*T*f/h from the
    top row to the bottom row (3.3 px here), within 0.5 px; the truth says so too."""
    world = fa.World.scene(buildings=[(0.0, 30.0, 2.0, 60.0, 1.0)], size=(200.0, 200.0))
    views = fa.sensors.ViewSet(world, [(0.0, 30.0, 31.0, math.pi / 2)],
                               {"fov_deg": FOV, "width": W, "height": H})
    v, T, h = 12.0, 0.03, 30.0
    expect = v * T * F / h
    c = fa.Conditions(readout_s=T, noise=False, auto_exposure=False)
    still = views.under(c)[0][0]
    moving, truth = views.under(c, velocity=(v, 0.0, 0.0))[0]

    def edge(img, row):            # sub-pixel column where the row crosses mid-level
        g = img[row, : W // 2].astype(float).sum(axis=1)
        i = int(np.argmax(np.abs(np.diff(g))))
        lo, hi = g[max(i - 4, 0)], g[min(i + 5, len(g) - 1)]
        mid = 0.5 * (lo + hi)
        k = next(j for j in range(max(i - 4, 0), i + 5) if (g[j] - mid) * (g[j + 1] - mid) <= 0)
        return k + (mid - g[k]) / (g[k + 1] - g[k])
    top, bottom = (edge(moving, 5), edge(moving, H - 6))
    s_top, s_bottom = edge(still, 5), edge(still, H - 6)
    assert s_top == pytest.approx(s_bottom, abs=0.05)           # a straight edge when still
    assert abs(abs(bottom - top) - expect * (H - 11) / (H - 1)) <= 0.75
    # the truth's skew is the ground's under the image centre (31 m: one rule with or
    # without haze, see sensors.conditions), the roof 1 m above it moves 1/30 more
    assert math.hypot(*truth.skew_px) == pytest.approx(v * T * F / 31.0, rel=0.02)


# -- weather -----------------------------------------------------------------------------
def test_weather_is_seeded_and_grows_with_severity():
    pytest.importorskip("albumentations")
    world = fa.World.scene(people=[(x, 0.0) for x in range(-6, 7, 3)])
    views = fa.sensors.ViewSet(world, [(0.0, 0.0, 25.0, 0.0)], {"fov_deg": FOV})
    ideal = views.ideal()[0][0].astype(float)
    for w in ("rain", "snow", "spatter"):
        change = []
        for sev in (1, 3, 5):
            c = fa.Conditions(weather=w, severity=sev, noise=False, auto_exposure=False)
            a = views.under(c, seed=1)[0][0]
            np.testing.assert_array_equal(a, views.under(c, seed=1)[0][0])
            change.append(float(np.abs(a.astype(float) - ideal).mean()))
        assert change[0] > 0.5 and change[2] > change[0], (w, change)


def test_bad_weather_is_refused_with_what_is_allowed():
    with pytest.raises(ConfigError, match=r"weather = 'hail' is not allowed.*'rain'"):
        fa.Conditions(weather="hail")
    with pytest.raises(ConfigError, match=r"severity = 6 is not allowed; expected an integer 1\.\.5"):
        fa.Conditions(weather="rain", severity=6)
    with pytest.raises(ConfigError, match="readout_s"):
        fa.Conditions(readout_s=-0.01)
    with pytest.raises(ConfigError, match="sun_azimuth_deg"):
        fa.Conditions(sun_azimuth_deg=400.0)


def test_the_conditions_strategy_draws_weather_and_shrinks_to_its_mildest_form():
    strat = fst.conditions(weather=("rain", "snow"), max_readout_s=0.05)
    c = find(strat, lambda c: c.weather == "rain", settings=settings(database=None))
    assert (c.weather, c.severity, c.readout_s, c.exposure_s) == ("rain", 1, 0.0, 0.0)
    c = find(strat, lambda c: c.readout_s > 0.01, settings=settings(database=None))
    assert c.weather is None and c.exposure_s == 0.0 and c.visibility_m == math.inf
    with pytest.raises(NoSuchExample):                         # not asked: no weather, no skew
        find(fst.conditions(), lambda c: c.weather is not None or c.readout_s > 0,
             settings=settings(database=None, max_examples=200))
