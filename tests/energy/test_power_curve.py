"""The forward-flight power curve against a published power-vs-speed measurement of a
quadrotor of the same class: Di Franco and Buttazzo (2016), a 1.3 kg quadrotor on 10x4.7 in
propellers (``airframe/power_curves.py``), against the 3DR Solo datasheet blueprint (1.5 kg,
10 in propellers). The measured curve: 7.2 % below hover at 7 m/s (its lowest), +49 % at
15 m/s. benchmarks/forward_flight.py --curve prints the whole curve."""

import pytest

import pytest_flockai as fa
from pytest_flockai.airframe.power_curves import DI_FRANCO_2016, STOLAROFF_2018, relative


def _level_power(speed):
    pilot = (fa.pilots.Hover(altitude=10.0) if speed == 0.0 else
             fa.pilots.Waypoints([(5000.0, 0.0, 10.0)], speed=speed))
    tel = fa.Mission(fa.drone("3dr-solo"), pilot, max_time_s=45.0).run().telemetry
    return float(tel.power_w[tel.index >= 35.0].mean())


@pytest.fixture(scope="module")
def solo_curve():
    hover = _level_power(0.0)
    return {v: _level_power(v) / hover - 1.0 for v in (7.0, 15.0)}


def test_the_published_curves_read_back():
    assert relative(DI_FRANCO_2016, 7.0) == pytest.approx(-0.072, abs=0.002)
    assert relative(DI_FRANCO_2016, 15.0) == pytest.approx(0.49, abs=0.01)
    assert relative(DI_FRANCO_2016, 0.0) == 0.0
    assert relative(STOLAROFF_2018, 13.0) is None     # beyond its fastest reading


def test_the_solo_dips_below_hover_at_7_m_s_as_a_measured_quadrotor_does(solo_curve):
    measured = relative(DI_FRANCO_2016, 7.0)
    assert solo_curve[7.0] < 0.0
    assert solo_curve[7.0] == pytest.approx(measured, abs=0.08)


def test_the_solo_at_15_m_s_costs_what_a_measured_quadrotor_does(solo_curve):
    assert solo_curve[15.0] == pytest.approx(relative(DI_FRANCO_2016, 15.0), abs=0.10)
