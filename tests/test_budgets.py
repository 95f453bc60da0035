"""Budgets: parsing, unit conversion to the registry's SI units, evaluation, errors."""

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pytest_flockai import kpis
from pytest_flockai.budgets import OPERATORS, Budget, parse
from pytest_flockai.errors import ConfigError, FlockAIError


@pytest.mark.parametrize("kpi, text, op, limit", [
    ("flight_time_s", ">= 24 min", ">=", 1440.0),
    ("flight_time_s", ">= 24min", ">=", 1440.0),
    ("flight_time_s", "<= 1 h", "<=", 3600.0),
    ("flight_time_s", "> 30", ">", 30.0),                       # bare number: SI
    ("inference_latency_p50_s", "<= 1.5 s", "<=", 1.5),
    ("inference_latency_p50_s", "<= 250 ms", "<=", 0.25),
    ("inference_latency_p50_s", "<=1.5s", "<=", 1.5),
    ("energy_share_proc", "< 25%", "<", 0.25),
    ("energy_share_proc", "< 0.25", "<", 0.25),
    ("crashed", "== 0", "==", 0.0),
    ("energy_total_j", "<= 300 kJ", "<=", 300e3),
    ("energy_total_j", "<= 2 Wh", "<=", 7200.0),
    ("energy_total_j", "<= 1.5e3 J", "<=", 1500.0),
    ("mean_power_w", "< 200 W", "<", 200.0),
    ("mean_power_w", "< 0.2 kW", "<", 200.0),
    ("distance_m", ">= 2 km", ">=", 2000.0),
    ("max_speed_mps", ">= 20 km/h", ">=", 20 / 3.6),
    ("max_speed_mps", "<= 15 m/s", "<=", 15.0),
    ("kbytes_out", "<= 50 KB", "<=", 50.0),
    ("kbytes_out", "<= 50 kB", "<=", 50.0),
    ("kbytes_out", "<= 2 MB", "<=", 2000.0),
    ("tracking_error_max_m", "<= 50 cm", "<=", 0.5),
    ("battery_remaining", ">= -0.5", ">=", -0.5),
])
def test_parse_converts_to_the_registry_unit(kpi, text, op, limit):
    b = parse(kpi, text)
    assert isinstance(b, Budget)
    assert (b.kpi, b.op, b.text) == (kpi, op, text.strip())
    assert math.isclose(b.limit, limit, rel_tol=1e-12)


@pytest.mark.parametrize("op, limit, actual, passed, margin", [
    ("<=", 10.0, 9.0, True, 1.0),
    ("<=", 10.0, 10.0, True, 0.0),
    ("<=", 10.0, 11.0, False, -1.0),
    ("<", 10.0, 10.0, False, 0.0),
    ("<", 10.0, 9.5, True, 0.5),
    (">=", 10.0, 12.0, True, 2.0),
    (">=", 10.0, 8.0, False, -2.0),
    (">", 10.0, 10.0, False, 0.0),
    ("==", 0.0, 0.0, True, 0.0),
    ("==", 0.0, 1.0, False, -1.0),
    ("==", 0.1 + 0.2, 0.3, True, 0.0),        # float noise is equal
])
def test_evaluate(op, limit, actual, passed, margin):
    b = parse("distance_m", f"{op} {limit!r}")
    got_passed, got_margin = b.evaluate(actual)
    assert got_passed is passed
    assert got_margin == pytest.approx(margin)


def test_evaluate_missing_or_nan_never_passes():
    b = parse("distance_m", "<= 10")
    for bad in (None, float("nan")):
        passed, margin = b.evaluate(bad)
        assert passed is False and math.isnan(margin)
    assert parse("endurance_s", ">= 10 min").evaluate(float("inf")) == (True, float("inf"))


@given(op=st.sampled_from(OPERATORS), limit=st.floats(-1e6, 1e6), actual=st.floats(-1e6, 1e6))
def test_margin_sign_agrees_with_verdict(op, limit, actual):
    b = parse("distance_m", f"{op} {limit!r}")
    passed, margin = b.evaluate(actual)
    assert passed == {"<": actual < limit, "<=": actual <= limit, ">": actual > limit,
                      ">=": actual >= limit, "==": math.isclose(actual, limit, rel_tol=1e-9,
                                                                abs_tol=1e-12)}[op]
    if passed:
        assert margin >= 0
    else:
        assert margin <= 0


def test_format_uses_the_unit_of_the_budget():
    assert parse("flight_time_s", ">= 24 min").format(720.0) == "12 min"
    assert parse("energy_share_proc", "< 25%").format(0.125) == "12.5%"
    assert parse("energy_total_j", "<= 2 Wh").format(3600.0) == "1 Wh"
    assert parse("flight_time_s", ">= 30").format(12.0) == "12 s"
    assert parse("crashed", "== 0").format(1.0) == "1"


# -- errors ---------------------------------------------------------------------------------
def _error(kpi, text) -> str:
    with pytest.raises(ConfigError) as info:
        parse(kpi, text)
    assert isinstance(info.value, (ValueError, FlockAIError))
    return str(info.value)


def test_unknown_kpi_suggests_close_names():
    msg = _error("flight_tme_s", ">= 24 min")
    assert "unknown KPI 'flight_tme_s'" in msg
    assert "did you mean: flight_time_s" in msg


@pytest.mark.parametrize("text, shown", [
    ("=> 24 min", "'=>'"), ("= 24 min", "'='"), ("!= 3 s", "'!='"), ("24 min", "no operator"),
    ("≤ 3 s", "'≤'"),
])
def test_bad_operator(text, shown):
    msg = _error("flight_time_s", text)
    assert "flight_time_s" in msg and repr(text) in msg
    assert shown in msg
    assert "allowed operators: <, <=, >, >=, ==" in msg


def test_unknown_unit_lists_the_allowed_ones():
    msg = _error("flight_time_s", ">= 24 mins")
    assert "unknown unit 'mins'" in msg and "flight_time_s" in msg and "'>= 24 mins'" in msg
    assert "s, ms, min, h" in msg
    assert "did you mean: min" in msg


@pytest.mark.parametrize("kpi, text", [
    ("flight_time_s", ">= 5 m"), ("flight_time_s", "< 25%"), ("energy_total_j", "<= 5 W"),
    ("energy_share_proc", "< 2 s"), ("kbytes_out", "<= 3 km/h"), ("max_speed_mps", "<= 3 m"),
])
def test_wrong_dimension(kpi, text):
    msg = _error(kpi, text)
    assert kpi in msg and repr(text) in msg
    assert "measures" in msg and "allowed units" in msg


@pytest.mark.parametrize("text", ["<= fast", "<=", "", "<= 1.5.3 s", "<= 1 s extra"])
def test_malformed(text):
    msg = _error("flight_time_s", text)
    assert "flight_time_s" in msg


@pytest.mark.parametrize("value", [5, 1.5, None, ("<=", 5)])
def test_budget_must_be_a_string(value):
    msg = _error("flight_time_s", value)
    assert "not a string" in msg and "'<= 1.5 s'" in msg


def test_custom_dotted_kpi_before_registration():
    assert parse("probe.metric", "<= 3").limit == 3.0
    b = parse("probe.payload", "<= 2 MB")
    assert (b.limit, b.dimension) == (2000.0, "kB")
    assert "unknown unit 'furlongs'" in _error("probe.metric", "<= 3 furlongs")
    assert "unknown KPI" in _error("nodot_metric", "<= 3")


def test_custom_dotted_kpi_after_registration_checks_the_unit():
    kpis.register("budgettest.latency", unit="s", better="lower")
    assert parse("budgettest.latency", "<= 20 ms").limit == pytest.approx(0.02)
    assert "measures length" in _error("budgettest.latency", "<= 3 m")
    kpis.register("budgettest.temp", unit="degC")
    assert parse("budgettest.temp", "<= 70 degC").limit == 70.0
    assert parse("budgettest.temp", "<= 70").limit == 70.0


def test_a_fleet_drones_dotted_kpi_resolves_like_its_own_name():
    from pytest_flockai.policy import register_kpis
    register_kpis("budgetteam", ("confirm",))
    name = "d1.policy.budgetteam.time_confirm_s"
    b = parse(name, "<= 2 min")
    assert (b.limit, b.dimension) == (120.0, "s")
    assert b.verdict(100.0).passed and not b.verdict(130.0).passed
    assert b.verdict(130.0).margin_text == "-0.1667 min"
    assert "measures length" in _error(name, "<= 3 m")
    assert kpis.get(name).unit == "s" and "drone d1" in kpis.get(name).description
    assert kpis.abs_tolerance(name) == kpis.UNIT_ABS_TOL["s"]
    # every way an un-prefixed name resolves, a drone's name resolves the same way
    for plain in ("flight_time_s", "cnn.recall.person", "recall.alt_0_10m", "cnn.energy_j",
                  "policy.budgetteam.triggers"):
        k, d = kpis.get(plain), kpis.get(f"drone-2.{plain}")
        assert (d.unit, d.better) == (k.unit, k.better), plain
    assert kpis.get("d1.fleet.makespan_s") is None      # fleet-wide: no per-drone copy
    assert kpis.get("d1.d2.policy.budgetteam.triggers") is None    # one drone prefix


def test_percent_only_for_fractions_not_counts():
    from pytest_flockai.budgets import parse
    from pytest_flockai import ConfigError
    assert parse("energy_share_proc", "< 25%").limit == 0.25
    assert parse("packets_out", "<= 100").limit == 100
    with pytest.raises(ConfigError, match="packets_out.*count"):
        parse("packets_out", "< 5%")
    with pytest.raises(ConfigError, match="crashed"):
        parse("crashed", "== 0 %")
