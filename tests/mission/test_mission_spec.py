"""A Mission is a frozen spec: keyword-only after the drone and the pilot, checked
once when built, changed only through a copy (``replace``) that is checked again."""

import dataclasses
import pickle
import queue

import pytest

import pytest_flockai as fa
from pytest_flockai.errors import ConfigError


def hover(**kw):
    return fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(1.0, 0.5), **kw)


@pytest.mark.parametrize("field, value", [("energy_hz", -5.0), ("fly_on", "estmate"),
                                          ("seed", -1), ("until", 1.0)])
def test_a_field_cannot_be_assigned_after_the_checks(field, value):
    m = hover()
    with pytest.raises(dataclasses.FrozenInstanceError, match=f"'{field}'"):
        setattr(m, field, value)
    assert getattr(m, field) == getattr(hover(), field)


@pytest.mark.parametrize("replace", [lambda m, **c: m.replace(**c), dataclasses.replace])
@pytest.mark.parametrize("changes, message", [
    ({"seed": -1}, r"Mission: seed = -1 is not allowed"),
    ({"fly_on": "estmate"}, r"fly_on = 'estmate' is not allowed.*did you mean: estimate"),
    ({"energy_hz": -5.0}, r"energy_hz = -5.0"),
    ({"until": 10.0, "max_time_s": 5.0}, r"until = 10 s is above max_time_s = 5 s"),
    ({"wind": "strong"}, r"wind = 'strong' is not allowed"),
])
def test_a_changed_copy_is_checked_again(replace, changes, message):
    with pytest.raises(ConfigError, match=message):
        replace(hover(), **changes)


def test_replace_names_an_unknown_field():
    with pytest.raises(ConfigError, match=r"sed is not a Mission field \(did you mean: seed"):
        hover().replace(sed=1)


def test_arguments_after_drone_and_pilot_are_keyword_only():
    with pytest.raises(TypeError, match="positional"):
        fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(1.0, 0.5), None)


def test_a_copy_flies_as_the_mission_built_with_its_values():
    base = hover(seed=1, wind=1.5)
    copy = base.replace(seed=5, until=0.8)
    assert (base.seed, base.until, copy.seed, copy.until) == (1, "landed", 5, 0.8)
    assert isinstance(copy.wind, fa.Wind) and copy.wind is base.wind
    built = hover(seed=5, wind=1.5, until=0.8)
    assert copy.run().kpis == built.run().kpis


def test_live_subscribers_stay_with_their_mission():
    m = hover()
    q: queue.Queue = queue.Queue()
    m.subscribe(q)
    assert m.replace(seed=2).subscribers == []
    assert pickle.loads(pickle.dumps(m)).subscribers == []
    assert m.subscribers == [q]


def _fleet(**kw):
    pilot = fa.pilots.Hover(2.0, 1.0)
    drones = [fa.FleetDrone(f"d{i}", fa.drone("crazyflie-2-1"), pilot, pad=(3.0 * i, 0.0))
              for i in range(2)]
    return fa.Fleet(drones, **kw)


def test_fleet_and_fleet_drone_are_frozen_specs_too():
    fleet = _fleet(until=2.0)
    fd = fleet.drones[0]
    with pytest.raises(dataclasses.FrozenInstanceError, match="'until'"):
        fleet.until = 3.0
    with pytest.raises(dataclasses.FrozenInstanceError, match="'seed'"):
        fd.seed = 2
    with pytest.raises(ConfigError, match=r"FleetDrone 'd0': seed = -1 is not allowed"):
        fd.replace(seed=-1)
    with pytest.raises(ConfigError, match=r"until = 'lnded' is not allowed"):
        fleet.replace(until="lnded")
    with pytest.raises(ConfigError, match=r"drones\[1\].pad = \(0.0, 0.0\).*two drones at one pad"):
        fleet.replace(drones=[fd, fleet.drones[1].replace(pad=(0.0, 0.0))])
    with pytest.raises(TypeError, match="positional"):
        fa.FleetDrone("d9", fa.drone("crazyflie-2-1"), fa.pilots.Hover(2.0, 1.0), (0.0, 0.0))
    later = fleet.replace(drones=[fd.replace(seed=5), fleet.drones[1]])
    assert later.seed == (5, 0) and later.missions[0].seed == 5 and fleet.seed == (0, 0)
    assert later.until == 2.0 and later.missions[1].until == 2.0


def test_a_camera_is_a_frozen_spec_too():
    """The camera's arguments are frozen as a Mission's are (its frames and truth stay
    per-flight state); ``replace`` builds a new camera, checked again."""
    cam = fa.sensors.Camera(320, 240, pitch_deg=-60.0, name="cam")
    with pytest.raises(dataclasses.FrozenInstanceError, match="'pitch_deg'.*replace"):
        cam.pitch_deg = 200.0
    with pytest.raises(dataclasses.FrozenInstanceError, match="'conditions'"):
        cam.conditions = fa.Conditions()
    with pytest.raises(ValueError, match="read-only"):
        cam.mount[2] = 1.0
    assert cam.pitch_deg == -60.0 and cam.mount[2] == -0.05
    with pytest.raises(ConfigError, match=r"Camera 'cam': pitch_deg = 200"):
        cam.replace(pitch_deg=200.0)
    with pytest.raises(ConfigError, match=r"fov is not a Camera field \(did you mean: fov_deg"):
        cam.replace(fov=90.0)
    wide = cam.replace(fov_deg=90.0, mount=(0.0, 0.0, -0.1))
    assert (wide.fov_deg, wide.width, wide.name, wide.pitch_deg) == (90.0, 320, "cam", -60.0)
    assert list(wide.mount) == [0.0, 0.0, -0.1] and cam.fov_deg == 60.0 and wide is not cam
    assert wide.lens.focal_px != cam.lens.focal_px               # derived state rebuilt
