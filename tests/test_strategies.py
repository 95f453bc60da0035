"""Hypothesis strategies and the documented @given pattern."""

import math

import pytest
from hypothesis import given, settings

import pytest_flockai as fa
from pytest_flockai import strategies as fst
from pytest_flockai.budgets import BudgetError, check, evaluate


@settings(max_examples=30, deadline=None, database=None, derandomize=True)
@given(w=fst.winds(max_speed=8.0), area=fst.pilot_areas(), kg=fst.payloads("dji-mavic-2-pro"))
def test_strategies_draw_valid_values(w, area, kg):
    assert math.hypot(w.mean[0], w.mean[1]) <= 8.0 + 1e-9 and w.gust_std >= 0
    (x0, y0), (x1, y1) = area
    assert x1 - x0 >= 20.0 - 1e-9 and y1 - y0 >= 20.0 - 1e-9
    d = fa.drone("dji-mavic-2-pro", payload_kg=kg)
    assert d.thrust_to_weight >= 1.6 - 1e-9


@settings(max_examples=5, deadline=None, database=None, derandomize=True)
@given(m=fst.missions("crazyflie-2-1", pilots=fst.hovers(2.0), until=5.0))
def test_missions_fly(m):
    r = m.run()
    assert r.kpis["flight_time_s"] > 0


def test_check_and_evaluate_without_pytest():
    r = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(1.0, 1.0)).run()
    v = evaluate(r, flight_time_s=">= 1 s")
    assert v[0]["passed"] and v[0]["margin"] > 0
    try:
        check(r, flight_time_s=">= 1 h")
    except BudgetError as e:
        assert "flight_time_s" in str(e) and "BROKEN" in str(e)
    else:
        raise AssertionError("check() did not raise")


@pytest.mark.slow
def test_hypothesis_finds_wind_breaking_a_flight_time_budget(pytester):
    # the Crazyflie's 1 m hover lasts 6.96 min in still air and more up to ~6 m/s (translational
    # lift), then less: 6.10 min at 8 m/s, 4.95 at 10; winds up to 12 m/s put the broken part of
    # the range within reach of the 15 derandomized examples on every hypothesis version tested
    pytester.makepyfile(
        """
        from hypothesis import given, settings
        import pytest_flockai as fa
        from pytest_flockai import strategies as fst
        from pytest_flockai.budgets import check

        @settings(max_examples=15, deadline=None, database=None, derandomize=True)
        @given(wind=fst.winds(max_speed=12.0, gusts=False))
        def test_hover_endurance(wind):
            r = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(1.0, 0.5), wind=wind).run()
            fst.target_margin(r, endurance_s=">= 6.8 min")
            check(r, endurance_s=">= 6.8 min")
        """
    )
    res = pytester.runpytest("-p", "no:cacheprovider")
    res.assert_outcomes(failed=1)
    out = res.stdout.str()
    # the shrunk wind: hypothesis 6.124 prints the builds() call (speed_mps=...), 6.170
    # the Wind object it built
    assert ("Falsifying example" in out or "Failing test case" in out) and (
        "speed_mps=" in out or "wind=Wind(mean=" in out)
    assert "endurance_s" in out and "BROKEN" in out
    assert "FailedHealthCheck" not in out
