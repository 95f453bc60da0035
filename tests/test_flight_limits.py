"""Rates, speeds and periods the simulation can honour (pytest_flockai.limits):
outside them a ConfigError naming the field, the value and the limit; inside, a
speed above the drone's own top speed is flown at that speed and logged."""

import pytest

import pytest_flockai as fa
from pytest_flockai import limits
from pytest_flockai.control.stages import top_speed
from pytest_flockai.ml import PythonModel

CF = fa.drone("crazyflie-2-1")


def test_a_pilot_faster_than_the_drone_logs_speed_capped_with_what_was_flown():
    mavic = fa.drone("dji-mavic-2-pro")
    top = top_speed(mavic, 1.225)
    assert 18.0 < top < 24.0                     # spec: 72 km/h = 20 m/s in S-mode
    r = fa.Mission(mavic, fa.pilots.Waypoints([(300.0, 0.0, 20.0)], speed=100.0)).run()
    (ev,) = [e for e in r.events if e["kind"] == "speed_capped"]
    assert ev["asked_mps"] == 100.0 and ev["top_mps"] == pytest.approx(top)
    flown = (r.telemetry["vx"] ** 2 + r.telemetry["vy"] ** 2).max() ** 0.5
    assert flown < 1.1 * top
    ok = fa.Mission(mavic, fa.pilots.Waypoints([(50.0, 0.0, 20.0)], speed=8.0)).run()
    assert not [e for e in ok.events if e["kind"] == "speed_capped"]


def test_energy_at_the_slowest_allowed_rate_stays_close_to_the_default():
    kw = dict(drone=fa.drone("dji-mavic-2-pro"),
              pilot=fa.pilots.Waypoints([(30, 0, 10), (0, 30, 10)], speed=8))
    ref = fa.Mission(**kw).run().kpis["energy_total_j"]
    slow = fa.Mission(**kw, energy_hz=limits.MIN_ENERGY_HZ).run().kpis["energy_total_j"]
    assert abs(slow / ref - 1) < 0.005


@pytest.mark.parametrize("make, field", [
    (lambda: fa.Mission(CF, fa.pilots.Hover(1, 1), energy_hz=0.5), "MIN_ENERGY_HZ"),
    (lambda: fa.Mission(CF, fa.pilots.Hover(1, 1), climb_speed=0.05), "MIN_VERTICAL_SPEED_MPS"),
    (lambda: fa.pilots.Hover(1, 1) and fa.pilots.Waypoints([(1, 1, 1)], speed=200),
     "MAX_SPEED_MPS"),
    (lambda: fa.Task(PythonModel(lambda f: 0.0, macs=1), period_s=1e-4), "MIN_TASK_PERIOD_S"),
])
def test_each_limit_names_itself_and_can_be_moved(make, field, monkeypatch):
    with pytest.raises(fa.ConfigError, match=f"limits.{field}"):
        make()
    low = field.startswith("MIN")
    monkeypatch.setattr(limits, field, getattr(limits, field) * (1e-3 if low else 1e3))
    make()
