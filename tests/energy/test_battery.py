"""The battery as an equivalent circuit: open-circuit voltage per
chemistry, internal resistance, I^2 R loss, sag under load, cut-off voltage."""

import importlib.resources as res
import re

import pytest

import pytest_flockai as fa
from pytest_flockai.energy import battery as cells
from pytest_flockai.errors import ConfigError


def _pack(**kw):
    args = dict(chemistry="lipo", cells=4, capacity_ah=3.85, resistance_ohm=0.0078, cutoff_v_per_cell=3.0)
    args.update(kw)
    return cells.Circuit(**args)


def test_open_circuit_voltage_curves_match_their_sources():
    # Chen and Rincon-Mora (2006) polymer cell: 4.10 V full, 3.80 V at half charge
    assert cells.ocv("lipo", 1.0) == pytest.approx(4.103, abs=0.005)
    assert cells.ocv("lipo", 0.5) == pytest.approx(3.803, abs=0.005)
    # Tremblay et al. (2007) Li-ion cell: 4.19 V full
    assert cells.ocv("li-ion", 1.0) == pytest.approx(4.194, abs=0.005)
    for chem in cells.CHEMISTRIES:
        v = [cells.ocv(chem, s / 20) for s in range(1, 21)]
        assert all(a < b for a, b in zip(v, v[1:])), chem      # rises with charge


def test_voltage_under_load_falls_with_state_of_charge_and_current():
    p = _pack()
    v_full = p.open_circuit_v()
    p.draw(120.0, 1.0)
    v_120_full = p.voltage_v
    assert v_120_full < v_full
    p.soc = 0.3
    p.draw(120.0, 1.0)
    v_120_low = p.voltage_v
    assert v_120_low < v_120_full - 0.5          # lower charge: lower voltage at the same load
    p.soc = 0.3
    p.draw(240.0, 1.0)
    assert p.voltage_v < v_120_low               # more current: more sag
    # sag and loss are the resistance's: V = OCV - I R, loss = I^2 R
    p.soc = 0.5
    loss = p.draw(200.0, 1.0)
    r = 4 * 0.0078 * cells.resistance_shape(0.5)
    assert p.voltage_v * p.current_a == pytest.approx(200.0, rel=1e-9)
    assert loss == pytest.approx(p.current_a ** 2 * r, rel=1e-9)


def test_a_hover_draws_the_voltage_down_and_reports_it():
    d = fa.drone("dji-mavic-2-pro", battery_mah=770, internal_resistance_mohm=7.8)
    r = fa.Mission(d, fa.pilots.Hover(altitude=10), until="battery_depleted").run()
    tel = r.telemetry
    hover = tel[tel.phase == "hover"]
    assert hover.battery_v.iloc[-1] < hover.battery_v.iloc[0] - 1.0
    assert r.kpis["battery_v_min"] == pytest.approx(tel.battery_v.min(), abs=0.05)
    assert r.kpis["battery_v_min"] < 4 * 3.6
    assert r.events[-1]["kind"] == "battery_depleted" and r.events[-1]["cause"] == "charge"


def test_cut_off_voltage_ends_the_flight_before_the_charge_is_drawn():
    # a worn pack: 10x the resistance; the sag crosses 3.0 V per cell while charge is left
    d = fa.drone("dji-mavic-2-pro", battery_mah=770, internal_resistance_mohm=78)
    r = fa.Mission(d, fa.pilots.Hover(altitude=10), until="battery_depleted").run()
    last = r.events[-1]
    assert r.end_reason == "battery_depleted" and last["cause"] == "cutoff_voltage"
    assert last["voltage_v"] < 4 * 3.0
    assert r.kpis["battery_remaining"] > 0.02


def test_a_heavier_payload_loses_more_than_the_mass_1_5_power_ratio_alone():
    """Mavic cells (7.8 mOhm), a fifth of the capacity to keep it short, hover to empty:
    no payload 340 s, 0.5 kg payload 184 s; the mass^1.5 scaling of the motors' power
    (proc and radio unchanged) predicts 187 s: the pack's I^2 R loss (1.6 % -> 2.8 %
    of the load) takes the rest."""
    def fly(payload):
        d = fa.drone("dji-mavic-2-pro", battery_mah=770, internal_resistance_mohm=7.8, payload_kg=payload)
        return d.mass_kg, fa.Mission(d, fa.pilots.Hover(altitude=10), until="battery_depleted").run()
    m0, light = fly(0.0)
    m1, heavy = fly(0.5)
    k0, k1 = light.kpis, heavy.kpis
    t0, t1 = k0["flight_time_s"], k1["flight_time_s"]
    p_motor = k0["energy_motors_j"] / t0
    p_rest = (k0["energy_proc_j"] + k0["energy_comm_j"]) / t0
    t1_mass_only = t0 * (p_motor + p_rest) / (p_motor * (m1 / m0) ** 1.5 + p_rest)
    assert t1 < 0.995 * t1_mass_only, (t0, t1, t1_mass_only)
    loss0 = k0["energy_battery_loss_j"] / k0["energy_total_j"]
    loss1 = k1["energy_battery_loss_j"] / k1["energy_total_j"]
    assert loss1 > 1.5 * loss0


@pytest.mark.parametrize("field, value, allowed", [
    ("cells", 0, "1 to 14"),
    ("chemistry", "nimh", "'lipo', 'li-ion'"),
    ("internal_resistance_mohm", -3.0, "> 0"),
])
def test_bad_battery_fields_name_the_file_field_and_what_is_allowed(tmp_path, field, value, allowed):
    src = (res.files("pytest_flockai.airframe") / "blueprints" / "dji-mavic-2-pro.toml").read_text()
    line = f"{field} = {value!r}".replace("'", '"')
    if re.search(rf"^{field} = .*$", src, flags=re.M):
        text = re.sub(rf"^{field} = .*$", line, src, count=1, flags=re.M)
    else:
        text = src.replace("[battery]\n", f"[battery]\n{line}\n", 1)
    p = tmp_path / "mydrone.toml"
    p.write_text(text)
    with pytest.raises(ConfigError) as e:
        fa.drone(str(p))
    msg = str(e.value)
    assert "mydrone.toml" in msg and "[battery]" in msg and field in msg and allowed in msg, msg


def test_cells_that_do_not_match_the_voltage_are_refused():
    with pytest.raises(ConfigError, match=r"voltage_v = 15.4 V over cells = 6 .* allowed: 3.0 to 4.4 V"):
        fa.drone("dji-mavic-2-pro", cells=6)
    assert fa.drone("dji-mavic-2-pro", cells=4, chemistry="li-ion").battery.cell_count == 4
