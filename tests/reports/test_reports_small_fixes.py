"""Smaller report and input fixes: the last telemetry row is not duplicated
when ``until`` is a number; two actors may not share a name (``Follow(score=...)``
would pick one silently)."""

import pytest

import pytest_flockai as fa
from pytest_flockai.errors import ConfigError


@pytest.mark.parametrize("until", [2.0, 2.05])
def test_the_last_telemetry_row_is_not_duplicated_when_until_is_a_number(until):
    r = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=30.0),
                   until=until).run()
    t = r.telemetry.index
    assert not t.duplicated().any()
    assert t[-1] == pytest.approx(until, abs=0.011)


def test_a_landed_flight_still_ends_with_its_final_row():
    r = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=1.0)).run()
    assert r.end_reason == "landed" and not r.telemetry.index.duplicated().any()
    assert r.telemetry["phase"].iloc[-1] == "landed"


def test_two_actors_with_one_name_are_refused():
    a = fa.actors.Person([(0.0, 0.0), (10.0, 0.0)], name="alice")
    b = fa.actors.Person([(5.0, 5.0), (10.0, 5.0)], name="alice")
    with pytest.raises(ConfigError, match=r"actors\[1\]\.name = 'alice' is not allowed: "
                                          r"actors\[0\] has that name"):
        fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0),
                   world=fa.World.scene(size=(50.0, 50.0)), actors=[a, b])
