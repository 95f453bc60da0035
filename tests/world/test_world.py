"""Worlds: urban layout, people, MJCF scenes, physics obstacles."""

import math

import mujoco
import numpy as np
import pytest

import pytest_flockai as fa
from pytest_flockai import ConfigError
from pytest_flockai.airframe.mjspec import build_spec
from pytest_flockai.world import urban as U
from pytest_flockai.world.truth import gimbal_pose, occluded, visible_people


@pytest.fixture(scope="module")
def city():
    return fa.World.urban(seed=7, size=(200.0, 160.0), people=80,
                          crowds=[(60.0, 40.0, 50, 5.0), (-50.0, -40.0, 30, 3.0)])


def test_urban_is_deterministic_from_its_seed(city):
    again = fa.World.urban(seed=7, size=(200.0, 160.0), people=80,
                           crowds=[(60.0, 40.0, 50, 5.0), (-50.0, -40.0, 30, 3.0)])
    assert np.array_equal(city.people, again.people)
    assert np.array_equal(city.buildings, again.buildings)
    assert np.array_equal(city.clothes, again.clothes)
    other = fa.World.urban(seed=8, size=(200.0, 160.0), people=80,
                           crowds=[(60.0, 40.0, 50, 5.0), (-50.0, -40.0, 30, 3.0)])
    assert not np.array_equal(city.people, other.people)
    # more scattered people never move the buildings
    more = fa.World.urban(seed=7, size=(200.0, 160.0), people=120,
                          crowds=[(60.0, 40.0, 50, 5.0), (-50.0, -40.0, 30, 3.0)])
    assert np.array_equal(city.buildings, more.buildings)


def test_buildings_do_not_overlap_each_other_home_or_crowds(city):
    b = city.buildings
    assert len(b) > 10
    for i in range(len(b)):
        for j in range(i + 1, len(b)):
            sep_x = abs(b[i, 0] - b[j, 0]) >= b[i, 2] + b[j, 2]
            sep_y = abs(b[i, 1] - b[j, 1]) >= b[i, 3] + b[j, 3]
            assert sep_x or sep_y, (i, j)
    for cx, cy, hx, hy, h in b:
        # distance from home / crowd centres to the footprint
        for (x, y, r) in [(0.0, 0.0, 15.0), (60.0, 40.0, 12.0), (-50.0, -40.0, 8.0)]:
            d = math.hypot(max(abs(x - cx) - hx, 0), max(abs(y - cy) - hy, 0))
            assert d >= r - 1e-9
        assert abs(cx) + hx <= 100 + 1e-9 and abs(cy) + hy <= 80 + 1e-9
        assert 6.0 <= h <= 45.0


def test_people_counts_positions_and_crowd_spread(city):
    P = city.people
    assert P.shape == (80 + 50 + 30, 3)
    assert np.all(P[:, 2] == 0.0)
    assert np.all(np.abs(P[:, 0]) <= 100) and np.all(np.abs(P[:, 1]) <= 80)
    assert not U.inside_buildings(P[:, :2], city.buildings).any()
    crowd = P[80:130, :2]
    assert np.allclose(crowd.mean(axis=0), (60, 40), atol=2.5)
    assert 3.5 < crowd.std(axis=0).mean() < 6.5
    # clothing colours vary
    assert len(np.unique(city.clothes_idx)) >= 8
    assert city.truth_points()[:, 2] == pytest.approx(np.full(len(P), 0.85))


def test_to_dict_and_repr(city):
    d = city.to_dict()
    assert d["name"] == "urban" and d["people"] == 160 and d["scattered"] == 80
    assert d["crowds"][0] == [60.0, 40.0, 50, 5.0] and d["buildings"] == len(city.buildings)
    assert "World.urban(seed=7" in repr(city)
    assert fa.World.empty().to_dict() == {"name": "empty", "people": 0}


@pytest.mark.parametrize("kw, words", [
    (dict(crowds=[(0.0, 0.0, 700, 5.0)]), ["crowds[0].count", "700", "<= 628"]),
    (dict(crowds=[(0.0, 0.0, 10)]), ["crowds[0]", "(x, y, count, spread_m)"]),
    (dict(crowds=[(500.0, 0.0, 10, 2.0)]), ["crowds[0].x", "500"]),
    (dict(crowds=[(0.0, 0.0, 10, 0.0)]), ["crowds[0].spread_m"]),
    (dict(crowds=[(0.0, 0.0, 2.5, 3.0)]), ["crowds[0].count", "2.5"]),
    (dict(people=-1), ["people", "-1"]),
    (dict(size=(10.0, 200.0)), ["size", ">= 20"]),
    (dict(seed=-3), ["seed", "-3"]),
    (dict(building_density=1.5), ["building_density", "1.5"]),
])
def test_bad_urban_arguments(kw, words):
    with pytest.raises(ConfigError) as e:
        fa.World.urban(**kw)
    for w in words:
        assert w in str(e.value)


def _drone_model(world):
    d = fa.drone("dji-mavic-2-pro")
    spec = build_spec(d, world, physics_dt=0.002)
    m = spec.compile()
    return m, mujoco.MjData(m)


def test_urban_compiles_with_the_drone_and_buildings_collide(city):
    m, d = _drone_model(city)
    assert m.body("drone").id == 1 and m.njnt == 1      # the world is static
    # few geoms: people are merged per colour
    assert m.ngeom < 120
    cx, cy, hx, hy, h = city.buildings[0]
    d.qpos[:3] = (cx + hx, cy, 5.0)                      # hull across the wall
    mujoco.mj_forward(m, d)
    hit = {m.geom(d.contact[i].geom[j]).name for i in range(d.ncon) for j in range(2)}
    assert "building0" in hit
    # people never collide: hovering inside the crowd gives no contact
    x, y, _ = city.people[100]
    d.qpos[:3] = (x, y, 1.0)
    mujoco.mj_forward(m, d)
    names = {m.geom(d.contact[i].geom[j]).name for i in range(d.ncon) for j in range(2)}
    assert not any(n.startswith("people") for n in names)


SCENE = """<mujoco>
  <asset><texture name="t" type="2d" builtin="checker" rgb1="1 0 0" rgb2="0 1 0" width="64" height="64"/>
  <material name="m" texture="t"/></asset>
  <worldbody>
    <light pos="0 0 10" dir="0 0 -1"/>
    <geom name="floor" type="plane" size="50 50 1" material="m"/>
    <body name="house" pos="10 0 2"><geom type="box" size="2 2 2"/></body>
    {people}
  </worldbody>
</mujoco>"""


def test_from_mjcf_finds_people_and_composes_with_the_drone(tmp_path):
    p = tmp_path / "scene.xml"
    p.write_text(SCENE.format(people="""
      <body name="person_a" pos="3 4 0.85"><geom type="capsule" size="0.2 0.6"/></body>
      <body name="person_b" pos="-3 -4 0.85"><geom type="capsule" size="0.2 0.6"/></body>"""))
    w = fa.World.from_mjcf(p)
    assert sorted(map(tuple, w.people.round(3))) == [(-3, -4, 0.85), (3, 4, 0.85)]
    assert w.occluders.shape == (1, 6)
    assert w.occluders[0] == pytest.approx([8, -2, 0, 12, 2, 4])
    m, d = _drone_model(w)
    assert m.body("drone").id == 1 and m.njnt == 1
    assert m.ntex >= 1 and m.nlight >= 1
    # geoms named person* (grouped up to "_") when no body is
    p2 = tmp_path / "geoms.xml"
    p2.write_text(SCENE.format(people="""
      <geom name="person1" type="capsule" pos="1 1 0.8" size="0.2 0.6"/>
      <geom name="person1_head" type="sphere" pos="1 1 1.6" size="0.1"/>
      <geom name="person2" type="capsule" pos="5 5 0.8" size="0.2 0.6"/>"""))
    assert len(fa.World.from_mjcf(p2).people) == 2
    # given positions win
    w3 = fa.World.from_mjcf(p2, people=[(0, 0, 0)])
    assert w3.people.tolist() == [[0.0, 0.0, 0.0]]


def test_from_mjcf_bad_files(tmp_path):
    with pytest.raises(ConfigError, match="nope.xml.*no such file"):
        fa.World.from_mjcf(tmp_path / "nope.xml")
    bad = tmp_path / "bad.xml"
    bad.write_text("<mujoco><worldbody><geom type='boxx'/></worldbody></mujoco>")
    with pytest.raises(ConfigError, match=r"bad\.xml.*not a valid MJCF"):
        fa.World.from_mjcf(bad)
    jointed = tmp_path / "joint.xml"
    jointed.write_text("<mujoco><worldbody><body><freejoint/><geom size='1'/></body>"
                       "</worldbody></mujoco>")
    with pytest.raises(ConfigError, match="joint.*static scenes only"):
        fa.World.from_mjcf(jointed)
    with pytest.raises(ConfigError, match="people"):
        fa.World.from_mjcf(_ok(tmp_path), people="x")


def _ok(tmp_path):
    p = tmp_path / "ok.xml"
    p.write_text(SCENE.format(people=""))
    return p


def test_projection_convention_and_occlusion():
    # a camera 30 m up looking straight down, image top = north (yaw 90 deg)
    pos, R = gimbal_pose((0, 0, 30), math.pi / 2, -90)
    assert R[:, 2] == pytest.approx([0, 0, 1])          # looks along -z
    pts = np.array([[0, 0, 0], [0, 5, 0], [5, 0, 0], [0, 100, 0]], dtype=float)
    idx, uv = visible_people(pts, pos, R, 60, 320, 240)
    assert idx.tolist() == [0, 1, 2]
    f = 120 / math.tan(math.radians(30))
    assert uv[0] == pytest.approx([160, 120])
    assert uv[1] == pytest.approx([160, 120 - f * 5 / 30])   # north is up
    assert uv[2] == pytest.approx([160 + f * 5 / 30, 120])   # east is right
    # a box between camera and the second point hides it
    box = np.array([[-1, 2.5, 10, 1, 4, 12]], dtype=float)
    assert occluded(pos, pts[:3], box).tolist() == [False, True, False]
    idx, _ = visible_people(pts, pos, R, 60, 320, 240, occluders=box)
    assert idx.tolist() == [0, 2]
