"""A backend never changes a verdict: the batched backends fly
what the mission asks or refuse it, and they see the crashes the per-flight core sees.

The end reasons of ``jax`` and the core agree exactly, except at a knife edge: where the
core's own verdict changes when its crash speed (``loop.CRASH_SPEED``, 2 m/s) moves by
``EDGE`` (1 %), the two backends' touchdowns (a hard floor against MuJoCo's soft contact,
docs/explanation/batched-backend.md) may fall either side of it. Energy, flight time and
the other KPIs keep the 2 % tolerance of tests/sweeps/test_sweep_batched.py, except that a
battery end (cut-off, or the pack's power limit, both checked on the 20 Hz energy clock)
may fall one energy sample apart: then the mean power agrees within 2 %.
"""

import math
import os

import pytest
from hypothesis import Phase, given, settings
from hypothesis import strategies as st

import pytest_flockai as fa
from pytest_flockai.mission import loop
from pytest_flockai.sweeps import axes as _axes
from pytest_flockai.sweeps import runner

NEEDS_JAX = "the batched backend needs JAX and MJX: pip install 'pytest-flockai[mjx]'"
REL = 0.02
EDGE = 0.01
#: the battery's clock (Mission(energy_hz=20)): a battery end is checked on it
ENERGY_PERIOD_S = 1.0 / 20.0
KPIS = ("sim_time_s", "flight_time_s", "energy_total_j", "energy_motors_j",
        "battery_remaining")
CRAZYFLIE_MAX_PAYLOAD = fa.drone("crazyflie-2-1").max_payload_kg()


def _hover(**kw):
    return fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=1.0),
                      **kw)


def _detour():
    return fa.policy.Rule("time_s > 0.5", then=[fa.policy.Land()])


@pytest.mark.parametrize("backend", ["jax", "mjx"])
def test_a_batched_backend_refuses_a_mission_with_a_policy(backend):
    """A policy is Python deciding during the flight: the batch would ignore it."""
    pytest.importorskip("jax", reason=NEEDS_JAX)
    with pytest.raises(fa.ConfigError) as exc:
        runner.sweep(_hover(policies=[_detour()]), backend=backend, payload_kg=[0.0])
    msg = str(exc.value)
    for word in (f"backend={backend!r}", "policies", "backend='process'"):
        assert word in msg


def test_auto_flies_a_policy_per_flight_and_says_why(monkeypatch):
    monkeypatch.setattr(runner, "AUTO_MIN_VARIANTS", 2)   # batch from 2 variants on
    df = runner.sweep(_hover(policies=[_detour()]), backend="auto", payload_kg=[0.0, 0.004])
    assert df.attrs["backend"] == "process" and df.attrs["backend_asked"] == "auto"
    assert "policies" in df.attrs["backend_why"]
    assert (df["sim_time_s"] < 3.0).all()          # the policy landed the drone early


def _core(values, crash_speed=None):
    """(end reason, KPIs) of one variant flown by the core (``crash_speed``: the crash
    threshold moved, to find the knife edge)."""
    m = _axes.apply(_hover(), values)
    if crash_speed is None:
        r = m.run()
    else:
        old, loop.CRASH_SPEED = loop.CRASH_SPEED, crash_speed
        try:
            r = m.run()
        finally:
            loop.CRASH_SPEED = old
    return r.end_reason, {**r.kpis, "sim_time_s": r.sim_time_s}


def _on_edge(values, reason):
    """Whether the core itself ends with ``reason`` once its crash speed moves by EDGE."""
    return any(_core(values, loop.CRASH_SPEED * (1 + k * EDGE))[0] == reason for k in (-1, 1))


def _check(plan, physics):
    from pytest_flockai.sweeps.batched import engine
    rows = engine.fly(_hover(), plan, None, physics)
    for values, row in zip(plan, rows):
        reason, kpis = _core(values)
        if row["end_reason"] != reason:
            assert _on_edge(values, row["end_reason"]), (values, reason, row["end_reason"])
            continue
        if reason == "battery_depleted" and abs(row["sim_time_s"] - kpis["sim_time_s"]) <= \
                ENERGY_PERIOD_S + 1e-9:           # a clocked end, one energy sample apart:
            a, b = (row["energy_total_j"] / row["sim_time_s"],       # the mean power agrees
                    kpis["energy_total_j"] / kpis["sim_time_s"])
            assert math.isclose(a, b, rel_tol=REL), (values, "mean power", a, b)
            continue
        for k in KPIS:
            a, b = row[k], kpis[k]
            assert math.isclose(a, b, rel_tol=REL) or (a != a and b != b), (values, k, a, b)


@pytest.mark.slow
@pytest.mark.jax
def test_jax_sees_the_crashes_of_a_crazyflie_in_strong_wind():
    """A Crazyflie blown down at 16 and 20 m/s hits the ground at 3-8 m/s: crashed on the
    core, on ``mjx``, and (now) on ``jax``: a touch in any physics substep counts."""
    pytest.importorskip("jax", reason=NEEDS_JAX)
    axes = dict(wind_mps=[16.0, 20.0], mission_seed=[0, 1])
    cpu = runner.sweep(_hover(), workers=1, **axes)
    bat = runner.sweep(_hover(), backend="jax", **axes)
    assert list(cpu["end_reason"]) == ["crashed"] * 4
    assert list(bat["end_reason"]) == list(cpu["end_reason"])
    for k in KPIS:
        assert ((bat[k] / cpu[k] - 1.0).abs() <= REL).all(), k


_variant = st.fixed_dictionaries({
    "wind_mps": st.floats(0.0, 25.0),
    "payload_kg": st.floats(0.0, CRAZYFLIE_MAX_PAYLOAD),
    "mission_seed": st.integers(0, 2 ** 16),
})


@pytest.mark.jax
@settings(max_examples=int(os.environ.get("FLOCKAI_VERDICT_EXAMPLES", "3")), deadline=None, derandomize=True, database=None,
          phases=[Phase.explicit, Phase.generate])     # a failure is reported, not shrunk
@pytest.mark.slow
@given(plan=st.lists(_variant, min_size=4, max_size=4))
def test_jax_and_the_core_agree_on_end_reasons_over_wind_payload_and_seed(plan):
    pytest.importorskip("jax", reason=NEEDS_JAX)
    _check(plan, "jax")


@pytest.mark.slow
@pytest.mark.jax
def test_mjx_and_the_core_agree_on_end_reasons_in_extreme_wind_at_the_payload_limit():
    """``mjx`` (a compile of about a minute on a CPU: a fixed matrix, not a search)."""
    pytest.importorskip("jax", reason=NEEDS_JAX)
    plan = [{"wind_mps": w, "payload_kg": p, "mission_seed": 1}
            for w in (0.0, 14.0, 25.0) for p in (0.0, CRAZYFLIE_MAX_PAYLOAD)]
    _check(plan, "mjx")
