"""Pads against the world and names against the fleet's KPIs: a pad inside a
building or against its wall is refused by name, ``survey(..., world=)`` puts its
default pads on free ground, a drone that cannot climb ends "takeoff_failed" with
its reason (never "landed"), and no drone may be named like a fleet KPI prefix."""

import pytest

import pytest_flockai as fa
from pytest_flockai.control.stages import CLIMB_GRACE_S
from pytest_flockai.fleet import pads

MAVIC = "dji-mavic-2-pro"
AREA = ((-50, -50), (50, 50))


def urban(seed=3):
    """seed 3: survey's default pad for drone 0 at (-55, -50) is inside a 7.5 m building."""
    return fa.World.urban(seed=seed, size=(200.0, 200.0), people=0)


def test_the_default_survey_pad_inside_a_building_is_refused_by_name():
    world = urban()
    parts = fa.fleet.survey(AREA, 3, spacing=15)
    assert "inside" in pads.problem(pads.obstacles(world), parts[0][1])
    with pytest.raises(fa.ConfigError, match=r"drone 'd0' pad = \(-55, -50\) is inside obstacle"):
        fa.Fleet([fa.FleetDrone(f"d{i}", fa.drone(MAVIC), p, pad=pad) for i, (p, pad)
                  in enumerate(parts)], world=world)


def test_survey_with_the_world_puts_every_pad_on_free_ground_and_every_drone_climbs():
    world = urban()
    parts = fa.fleet.survey(AREA, 3, spacing=15, altitude=40, world=world)
    obs = pads.obstacles(world)
    assert all(pads.problem(obs, pad) is None for _, pad in parts)
    default = [pad for _, pad in fa.fleet.survey(AREA, 3, spacing=15)]
    assert parts[0][1] != default[0] and [p for _, p in parts[1:]] == default[1:]   # moved if needed
    short = [(fa.pilots.Hover(altitude=40.0, duration=2.0), pad) for _, pad in parts]
    res = fa.Fleet([fa.FleetDrone(f"d{i}", fa.drone(MAVIC), p, pad=pad) for i, (p, pad)
                    in enumerate(short)], world=world).run()
    for name, r in res.drones.items():
        assert r.end_reason == "landed", name
        assert r.telemetry["z"].max() > 30.0, name


def test_a_pad_against_a_wall_is_refused():
    world = fa.World.scene(buildings=[(0.0, 0.0, 5.0, 5.0, 6.5)], size=(60.0, 60.0))
    hover = fa.pilots.Hover(10.0, 1.0)
    with pytest.raises(fa.ConfigError, match=r"'a' pad = \(5.4, 0\) is 0.40 m from the wall"):
        fa.Fleet([fa.FleetDrone("a", fa.drone(MAVIC), hover, pad=(5.4, 0.0))], world=world)
    fa.Fleet([fa.FleetDrone("a", fa.drone(MAVIC), hover, pad=(6.5, 0.0))], world=world)


def test_a_drone_that_cannot_climb_fails_with_its_reason_never_landed():
    """A drone once stood inside a 6.5 m building and "landed" after a normal
    looking flight; a single Mission (home at the origin) still can stand there."""
    world = fa.World.scene(buildings=[(0.0, 0.0, 5.0, 5.0, 6.5)], size=(60.0, 60.0))
    r = fa.Mission(fa.drone(MAVIC), fa.pilots.Hover(10.0, 5.0), world=world).run()
    assert r.end_reason == "takeoff_failed"
    (ev,) = [e for e in r.events if e["kind"] == "takeoff_failed"]
    assert ev["climbed_m"] < 0.5 and ev["target_m"] == pytest.approx(10.0, abs=0.1)
    assert "blocked" in ev["reason"] and "too weak" in ev["reason"]
    assert not [e for e in r.events if e.get("stage") in ("pilot", "landed")]
    assert r.kpis["flight_time_s"] < 10.0 + CLIMB_GRACE_S
    free = fa.Mission(fa.drone(MAVIC), fa.pilots.Hover(10.0, 5.0)).run()
    assert free.end_reason == "landed"


@pytest.mark.parametrize("name", ["fleet", "ground", "link", "FLEET"])
def test_a_drone_named_like_a_fleet_kpi_prefix_is_refused(name):
    with pytest.raises(fa.ConfigError, match=f"name = '{name}' is not allowed.*fleet.energy"):
        fa.FleetDrone(name, fa.drone(MAVIC), fa.pilots.Hover(10.0, 1.0))
    fa.FleetDrone(name + "1", fa.drone(MAVIC), fa.pilots.Hover(10.0, 1.0))
