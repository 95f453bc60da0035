"""fa.sweep: variants of a mission flown by the per-flight core, one row each."""

from pathlib import Path

import pandas as pd
import pytest

import pytest_flockai as fa
from pytest_flockai.errors import SimulationError

MODELS = Path(__file__).resolve().parents[2] / "fixtures" / "models"


def _base(**kw):
    return fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=1.0), **kw)


class FailAbovePayload(fa.Clocked):
    """Raises a SimulationError in flights whose payload is above a limit."""
    period_s = 0.5

    def __init__(self, limit_kg):
        self.limit_kg = limit_kg

    def bind(self, run):
        super().bind(run)
        self.run = run

    def step(self, t):
        self.advance_clock()
        if self.run.mission.drone.payload_kg > self.limit_kg:
            raise SimulationError("payload over the test's limit")


def test_grid_is_the_full_factorial_with_kpis_and_verdicts():
    df = fa.sweep(_base(), payload_kg=[0.0, 0.008], wind_mps=[0.0, 2.0], workers=1,
                  budgets={"flight_time_s": "<= 3.6 s"})
    assert list(df["payload_kg"]) == [0.0, 0.0, 0.008, 0.008]
    assert list(df["wind_mps"]) == [0.0, 2.0, 0.0, 2.0]
    assert (df["end_reason"] == "landed").all() and df["error"].isna().all()
    # heavier drone: more energy than the same wind without payload
    assert (df["energy_total_j"][2:].to_numpy() > df["energy_total_j"][:2].to_numpy()).all()
    assert list(df["ok"]) == list(df["flight_time_s"] <= 3.6)
    assert list(df["ok_flight_time_s"]) == list(df["ok"])
    # the same variant flown alone gives the same KPIs
    alone = _base()
    alone.drone.payload_kg = 0.008
    assert alone.run().kpis["energy_total_j"] == df["energy_total_j"][2]


def test_wind_direction_and_blueprint_fields_reach_the_flight():
    df = fa.sweep(_base(), wind_mps=[3.0], wind_dir_deg=[0.0, 90.0], battery_mah=[250.0],
                  until=[2.0], workers=1)
    assert set(df["sim_time_s"].round(6)) == {2.0}
    assert df["energy_total_j"][0] != df["energy_total_j"][1]


def test_random_and_lhs_samples_are_seeded():
    kw = dict(payload_kg=(0.0, 0.01), mission_seed=(0, 3), samples=4, workers=1, until=[0.5])
    a = fa.sweep(_base(), method="lhs", seed=1, **kw)
    b = fa.sweep(_base(), method="lhs", seed=1, **kw)
    c = fa.sweep(_base(), method="lhs", seed=2, **kw)
    pd.testing.assert_frame_equal(a, b)
    assert list(a["payload_kg"]) != list(c["payload_kg"])
    # Latin hypercube: one sample in each quarter of the payload range
    assert sorted(int(p / 0.0025) for p in a["payload_kg"]) == [0, 1, 2, 3]
    assert all(isinstance(s, int) and 0 <= s <= 3 for s in a["mission_seed"])
    r = fa.sweep(_base(), method="random", seed=1, **kw)
    assert len(r) == 4 and r["payload_kg"].between(0.0, 0.01).all()


@pytest.mark.slow
def test_same_dataframe_with_one_or_two_worker_processes():
    kw = dict(payload_kg=[0.0, 0.006], mission_seed=[0, 1], budgets={"energy_total_j": "<= 25 J"})
    one = fa.sweep(_base(), workers=1, **kw)
    two = fa.sweep(_base(), workers=2, **kw)
    pd.testing.assert_frame_equal(one, two)
    assert len(two) == 4


def test_a_failing_variant_is_a_row_with_its_error():
    base = _base(components=[FailAbovePayload(0.005)])
    df = fa.sweep(base, payload_kg=[0.0, 0.008], workers=1, budgets={"flight_time_s": "> 0 s"})
    assert df["error"][0] is None and df["end_reason"][0] == "landed"
    assert "SimulationError: payload over the test's limit" in df["error"][1]
    assert list(df["ok"]) == [True, False]


def test_a_base_mission_that_cannot_go_to_other_processes_is_a_config_error():
    class Local(FailAbovePayload):       # defined in a function: pickle cannot find it
        pass
    with pytest.raises(fa.ConfigError) as exc:
        fa.sweep(_base(components=[Local(1.0)]), payload_kg=[0.0, 0.001], workers=2)
    assert "cannot be pickled" in str(exc.value) and "workers=1" in str(exc.value)
    df = fa.sweep(_base(components=[Local(1.0)]), payload_kg=[0.0], until=[0.5], workers=1)
    assert df["error"].isna().all()


def test_sweep_flights_are_not_recorded_one_by_one():
    seen = []
    with fa.recording(lambda r, m: seen.append(r)):
        fa.sweep(_base(), payload_kg=[0.0], until=[0.5], workers=1)
    assert seen == []


@pytest.mark.parametrize("kwargs, words", [
    (dict(paylod_kg=[0.1]), ["unknown axis 'paylod_kg'", "payload_kg"]),
    (dict(payload_kg=0.1), ["payload_kg = 0.1", "list"]),
    (dict(payload_kg="0.1"), ["payload_kg = '0.1'", "list"]),
    (dict(payload_kg=[]), ["payload_kg is empty"]),
    (dict(payload_kg=[[0.0, 0.1]]), ["payload_kg", "shape (1, 2)"]),
    (dict(payload_kg=[-0.1]), ["axis payload_kg = -0.1", "payload_kg"]),
    (dict(payload_kg=["heavy"]), ["axis payload_kg = 'heavy'"]),
    (dict(mission_seed=[1.5]), ["mission_seed = 1.5", "integer"]),
    (dict(wind_mps=[-1.0]), ["wind_mps = -1.0", ">= 0"]),
    (dict(payload_kg=(0.0, 0.1, 0.2), method="lhs", samples=3), ["3 entries", "(low, high)"]),
    (dict(payload_kg=(0.2, 0.1), method="random", samples=3), ["high < low"]),
    (dict(payload_kg=[0.0], samples=3), ["samples = 3", "grid"]),
    (dict(payload_kg=(0.0, 0.1), method="lhs"), ["samples = None", "integer >= 1"]),
    (dict(payload_kg=[0.0], method="sobol"), ["method = 'sobol'", "grid, random, lhs"]),
    (dict(payload_kg=[0.0], workers=0), ["workers = 0"]),
    (dict(payload_kg=[0.0], budgets={"flight_time_s": "long"}), ["flight_time_s", "'long'"]),
    (dict(payload_kg=[0.0], backend="gpu"), ["backend = 'gpu'", "'process'"]),
    (dict(payload_kg=[0.0], device="gpu"), ["device = 'gpu'", "backend='mjx'"]),
    (dict(payload_kg=[0.0], backend="mjx", device="abacus"), ["device = 'abacus'", "'gpu'"]),
    (dict(), ["no axis"]),
])
def test_bad_input_is_a_config_error_naming_it(kwargs, words):
    with pytest.raises(fa.ConfigError) as exc:
        fa.sweep(_base(), **kwargs)
    for w in words:
        assert w in str(exc.value)


def test_a_task_with_a_batched_backend_is_refused_naming_the_task():
    m = fa.Mission(fa.drone("dji-mavic-2-pro"), fa.pilots.Hover(altitude=10.0, duration=1.0),
                   tasks=[fa.Task(fa.ml.OnnxModel(str(MODELS / "crowd_cnn.onnx")), name="crowd")])
    with pytest.raises(fa.ConfigError) as exc:
        fa.sweep(m, payload_kg=[0.0], backend="mjx")
    assert "tasks = ['crowd']" in str(exc.value) and "backend='process'" in str(exc.value)


def test_an_axis_a_datasheet_derivation_depends_on_is_refused_on_a_datasheet_drone():
    """Setting mass_kg or the pack voltage on a built datasheet drone would not derive its
    rotors, motors and drag again (fa.drone(..., mass_kg=) does): a ConfigError, not a
    different drone flown silently. payload_kg stays allowed (the same drone carrying more)."""
    base = fa.Mission(fa.drone("dji-mavic-2-pro-datasheet"), fa.pilots.Hover(10.0, 1.0), until=2.0)
    for axis in ("mass_kg", "battery_v"):
        with pytest.raises(fa.ConfigError, match=f"{axis}.*derives its rotors"):
            fa.sweep(base, **{axis: [1.0]})
    assert len(fa.sweep(base, payload_kg=[0.0, 0.1])) == 2
