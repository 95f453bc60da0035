"""The datasheet-level blueprints of the issue-15 validation table (benchmarks/validation.py):
each loads and validates, keeps to the global rules its header states, refuses a bad value
with the field, and hovers stably for 10 s. The flights to depletion are in the benchmark."""

import math
from pathlib import Path

import numpy as np
import pytest

import pytest_flockai as fa
from pytest_flockai import ConfigError

NEW = ["dji-mini-3-pro", "dji-air-2s", "dji-phantom-4-pro-v2", "dji-inspire-2", "dji-matrice-300-rtk"]
RHO = 1.225
BLUEPRINTS = Path(fa.__file__).parent / "airframe" / "blueprints"


def test_new_blueprints_are_listed_and_span_sub_250_g_to_over_3_kg():
    assert set(NEW) <= set(fa.blueprints())
    masses = [fa.drone(n).airframe.mass_kg for n in NEW]
    assert min(masses) < 0.250 and max(masses) > 3.0


@pytest.mark.parametrize("name", NEW + ["dji-mavic-2-pro-datasheet"])
def test_blueprint_is_datasheet_level(name):
    """Issue 15, session 4: the validation blueprints give datasheet values only; the rotor
    coefficients and efficiencies come from airframe/datasheet.py, the same for every drone."""
    d = fa.drone(name)
    text = (BLUEPRINTS / f"{name}.toml").read_text()
    assert "[datasheet]" in text and "fitted:" not in text
    for key in ("thrust_coeff", "torque_coeff", "figure_of_merit", "motor_efficiency",
                "wake_interference", "drag_area_m2", "inertia_kg_m2"):
        assert f"\n{key} =" not in text, key
    ds = d.datasheet
    D = d.rotor.diameter_m
    assert d.rotor.thrust_coeff == pytest.approx(ds["ct"] * RHO * D ** 4 / (4 * math.pi ** 2))
    assert d.energy.component("motors").figure_of_merit == pytest.approx(ds["figure_of_merit"])
    assert d.energy.component("motors").motor_efficiency == pytest.approx(ds["motor_efficiency"])
    # no Kv on the datasheet: the design thrust-to-weight 2.5 sets the top rotor speed
    assert d.thrust_to_weight_at(RHO) == pytest.approx(2.5, rel=0.01)


@pytest.mark.parametrize("name", NEW)
def test_blueprint_hovers_stably_for_10_s(name):
    r = fa.Mission(fa.drone(name), fa.pilots.Hover(altitude=5.0, duration=10.0), until=25.0,
                   return_home=False).run()
    assert r.end_reason == "landed" and r.kpis["crashed"] == 0
    tel = r.telemetry
    hold = tel[tel.stage == "pilot"]
    hold = hold[hold.index > hold.index[0] + 3.0]          # the climb has settled
    assert hold.index[-1] - hold.index[0] > 5.0
    assert np.max(np.abs(hold.z - 5.0)) < 0.2
    assert np.max(np.hypot(hold.x, hold.y)) < 0.2
    assert np.max(np.abs(hold.roll)) < 0.05 and np.max(np.abs(hold.pitch)) < 0.05


def test_bad_cell_count_in_a_new_blueprint_names_the_field(tmp_path):
    text = (BLUEPRINTS / "dji-air-2s.toml").read_text()
    assert "cells = 3 " in text
    bad = tmp_path / "air.toml"
    bad.write_text(text.replace("cells = 3 ", "cells = 0 "))
    with pytest.raises(ConfigError, match="cells = 0"):
        fa.drone(str(bad))


@pytest.mark.parametrize("name", NEW)
def test_blueprint_holds_a_gusty_5_mps_wind_for_10_s(name):
    # measured (seed 0): largest horizontal error 0.47 m (Air 2S) to 1.58 m (Matrice 300),
    # altitude within 0.13 m, pitch under 5.4 deg
    wind = fa.Wind(mean=(5.0, 0.0, 0.0), gust_std=1.0)
    r = fa.Mission(fa.drone(name), fa.pilots.Hover(altitude=5.0, duration=10.0), until=25.0,
                   return_home=False, wind=wind, seed=0).run()
    assert r.end_reason == "landed" and r.kpis["crashed"] == 0
    tel = r.telemetry
    hold = tel[tel.stage == "pilot"]
    hold = hold[hold.index > hold.index[0] + 3.0]
    assert np.max(np.abs(hold.z - 5.0)) < 0.3
    assert np.max(np.hypot(hold.x, hold.y)) < 2.5
    assert np.max(np.abs(hold.pitch)) < math.radians(10.0)
