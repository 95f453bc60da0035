"""The MuJoCo model of a world is compiled once and reused by the next flights over
it (``airframe/model_cache.py``): counted in builds, and the reused model flies
exactly as a freshly built one."""

import math

import pytest

import pytest_flockai as fa
from pytest_flockai.airframe import model_cache

MAVIC = "dji-mavic-2-pro"

# these tests count model builds, so every flight must be flown: a flight served from
# the flight cache (on by default, under pytest's cache directory) builds nothing
pytestmark = pytest.mark.flockai_cache("off")


@pytest.fixture(autouse=True)
def empty_cache():
    model_cache.clear()
    yield
    model_cache.clear()


def town(people=120, seed=2):
    return fa.World.urban(seed=seed, size=(120.0, 120.0), people=people)


def hover(world, wind=None, blueprint=MAVIC):
    return fa.Mission(fa.drone(blueprint), fa.pilots.Hover(2.0), world=world, wind=wind, until=1.5,
                      seed=4)


def same(a, b) -> bool:
    return a.keys() == b.keys() and all(
        a[k] == b[k] or (math.isnan(a[k]) and math.isnan(b[k])) for k in a)


def test_the_second_flight_over_a_world_reuses_its_model_and_flies_the_same():
    world = town()
    first = hover(world).run()
    assert model_cache.info()["builds"] == 1
    second = hover(world).run()
    info = model_cache.info()
    assert (info["builds"], info["reuses"], info["models"]) == (1, 1, 1)
    assert same(first.kpis, second.kpis)


def test_a_world_built_alike_reuses_the_model_and_an_edited_world_does_not():
    hover(town()).run()
    hover(town()).run()                          # another object, the same content
    assert model_cache.info()["builds"] == 1
    hover(town(people=121)).run()
    hover(town(seed=3)).run()
    edited = town()
    assert len(edited.buildings)
    edited.buildings = edited.buildings.copy()
    edited.buildings[0, 4] += 5.0                # a building raised after it was built
    hover(edited).run()
    assert model_cache.info()["builds"] == 4


def test_other_drones_get_their_own_model():
    world = town()
    hover(world).run()
    hover(world, blueprint="dji-air-2s").run()
    assert model_cache.info()["builds"] == 2


def test_a_flight_changing_its_model_leaves_the_next_flights_model_alone():
    """The wind sets the model's ``opt.wind`` during a flight: the next flight over
    the same world, in calm air, flies as the first calm one did."""
    world = town()
    calm = hover(world).run()
    windy = hover(world, wind=fa.Wind(mean=(6.0, 0.0, 0.0))).run()
    again = hover(world).run()
    assert model_cache.info()["builds"] == 1
    assert not same(calm.kpis, windy.kpis)
    assert same(calm.kpis, again.kpis)


def test_fleets_over_one_world_reuse_their_model():
    world = town()

    def fleet():
        return fa.Fleet([fa.FleetDrone(f"d{i}", fa.drone(MAVIC), fa.pilots.Hover(2.0),
                                       pad=(4.0 * i, 0.0), seed=i) for i in range(2)],
                        world=world, until=1.5)
    a, b = fleet().run(), fleet().run()
    assert model_cache.info()["builds"] == 1
    assert same(a.kpis, b.kpis)
