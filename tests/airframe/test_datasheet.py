"""Datasheet-level blueprints: airframe/datasheet.py derives the rotor
coefficients, figure of merit, motor efficiency and body from a maker's figures. The endurance
table against published figures is a benchmark (benchmarks/validation.py), not a test."""

import math
from pathlib import Path

import pytest

import pytest_flockai as fa
from pytest_flockai import ConfigError
from pytest_flockai.airframe import datasheet as dsm

IN = 0.0254
RHO = 1.225
BLUEPRINTS = Path(fa.__file__).parent / "airframe" / "blueprints"


def test_propeller_model_reproduces_its_uiuc_anchor():
    # UIUC Propeller Data Site, APC 9x4.7 static: C_T 0.11, C_P 0.045 (FM 0.65)
    ct, cp, fm = dsm.propeller(9 * IN, 4.7 * IN, 2)
    assert ct == pytest.approx(0.11, rel=0.02)
    assert cp == pytest.approx(0.045, rel=0.02)
    assert fm == pytest.approx(0.65, rel=0.02)


def test_thrust_coefficient_rises_with_pitch_to_diameter_ratio_and_blades():
    cts = [dsm.propeller(10 * IN, p * IN, 2)[0] for p in (3.0, 4.5, 6.0, 8.0)]
    assert cts == sorted(cts) and cts[-1] > 1.5 * cts[0]
    # power rises with pitch too (more thrust, and induced power grows as C_T^1.5)
    cps = [dsm.propeller(10 * IN, p * IN, 2)[1] for p in (3.0, 8.0)]
    assert cps[1] > cps[0]
    assert dsm.propeller(10 * IN, 4.5 * IN, 3)[0] > dsm.propeller(10 * IN, 4.5 * IN, 2)[0]


def test_figure_of_merit_rises_with_reynolds_number():
    fms = [dsm.propeller(8 * IN, 4 * IN, 2, re)[2] for re in (1e4, 3e4, 1e5, 3e5)]
    assert fms == sorted(fms)
    assert fms[0] < 0.5 < 0.7 < fms[-1]


def test_small_propellers_hover_at_lower_reynolds_number_and_figure_of_merit():
    small = dsm.hover_propeller(6 * IN, 3 * IN, 2, 0.249 * 9.81 / 4)
    large = dsm.hover_propeller(21 * IN, 10 * IN, 2, 6.3 * 9.81 / 4)
    assert small[2] < large[2]
    # hover speed of the large rotor: thrust = C_T rho n^2 D^4
    ct, _, _, omega = large
    n = omega / (2 * math.pi)
    assert ct * RHO * n ** 2 * (21 * IN) ** 4 == pytest.approx(6.3 * 9.81 / 4, rel=1e-6)


def test_motor_efficiency_from_kv_rm_i0():
    kv = 900 * 2 * math.pi / 60
    base = dsm.motor_efficiency(0.05, 600.0, kv_rad=kv, rm=0.2, i0=0.3)
    assert 0.5 < base < 1.0
    assert dsm.motor_efficiency(0.05, 600.0, kv_rad=kv, rm=0.4, i0=0.3) < base
    assert dsm.motor_efficiency(0.05, 600.0, kv_rad=kv, rm=0.2, i0=0.6) < base
    # by hand: I = Q Kv + I0, V = omega / Kv + I Rm, eta = Q omega / (V I)
    i = 0.05 * kv + 0.3
    assert base == pytest.approx(0.05 * 600 / ((600 / kv + i * 0.2) * i))


def _mini(tmp_path, **edits):
    text = (BLUEPRINTS / "dji-mini-3-pro.toml").read_text()
    for old, new in edits.items():
        assert old in text, old
        text = text.replace(old, new)
    p = tmp_path / "mini.toml"
    p.write_text(text)
    return p


def test_datasheet_motor_values_and_user_fields_override_the_defaults(tmp_path):
    default = fa.drone("dji-mini-3-pro")
    worse = fa.drone(str(_mini(tmp_path, **{"prop_blades = 2 ": "motor_rm_ohm = 4.0\nprop_blades = 2 "})))
    assert worse.datasheet["motor_rm_ohm"] == 4.0
    assert worse.energy.component("motors").motor_efficiency < default.energy.component("motors").motor_efficiency
    # a field the user knows better wins over the derived one
    own = fa.drone(str(_mini(tmp_path, **{"\n[radio]\n": "\n[energy]\nmotor_efficiency = 0.9\n\n[radio]\n",
                                          "\n[battery]\n": "\n[rotor]\nthrust_coeff = 2.0e-6\n\n[battery]\n"})))
    assert own.energy.component("motors").motor_efficiency == 0.9
    assert own.rotor.thrust_coeff == 2.0e-6


def test_a_given_kv_sets_the_top_rotor_speed(tmp_path):
    d = fa.drone(str(_mini(tmp_path, **{"prop_blades = 2 ": "motor_kv = 1800.0\nprop_blades = 2 "})))
    ds = d.datasheet
    kv = 1800.0 * 2 * math.pi / 60
    w = d.rotor.max_speed_rad_s
    # the motor equation at the pack's nominal voltage: V = omega / Kv + (km omega^2 Kv + I0) Rm
    v = w / kv + (d.rotor.torque_coeff * w * w * kv + ds["motor_i0_a"]) * ds["motor_rm_ohm"]
    assert v == pytest.approx(7.38, rel=1e-3)
    assert w < 7.38 * kv
    with pytest.raises(ConfigError, match="thrust-to-weight"):      # a Kv far too low
        fa.drone(str(_mini(tmp_path, **{"prop_blades = 2 ": "motor_kv = 300.0\nprop_blades = 2 "})))


@pytest.mark.parametrize("old, new, field, allowed", [
    ("prop_blades = 2 ", "motor_kv = -900.0\nprop_blades = 2 ", "motor_kv", "allowed: > 0"),
    ("prop_pitch_in = 3.0 ", "prop_pitch_in = 0.0 ", "prop_pitch_in", "allowed: > 0"),
    ("prop_blades = 2 ", "prop_blades = 1 ", "prop_blades", "allowed: a whole number"),
    ("cells = 2 ", "cells = 0 ", "cells", "allowed: a whole number of cells"),
    ('chemistry = "li-ion"', 'chemistry = "nimh"', "chemistry", "allowed"),
    ("prop_diameter_in = 6.0 ", "prop_diameter_in = 152.4 ", "prop_diameter_in", "allowed: 0.8 to 63"),
    ("prop_blades = 2 ", 'motor_type = "brushed"\nprop_blades = 2 ', "motor_type", "brushed-coreless"),
])
def test_bad_datasheet_values_name_the_file_the_field_and_what_is_allowed(tmp_path, old, new, field, allowed):
    p = _mini(tmp_path, **{old: new})
    with pytest.raises(ConfigError) as exc:
        fa.drone(str(p))
    msg = str(exc.value)
    assert str(p) in msg and field in msg and allowed in msg


def test_unknown_datasheet_key_suggests_the_close_one(tmp_path):
    p = _mini(tmp_path, **{"prop_blades = 2 ": "motor_kvv = 900.0\nprop_blades = 2 "})
    with pytest.raises(ConfigError, match="unknown key 'motor_kvv'.*motor_kv"):
        fa.drone(str(p))


def test_motors_sized_for_the_maximum_takeoff_mass_lose_less_at_hover(tmp_path):
    # the M300's published 9 kg maximum take-off mass: larger motors, more motor constant,
    # less copper loss at the 6.3 kg hover
    text = (BLUEPRINTS / "dji-matrice-300-rtk.toml").read_text()
    line = next(ln for ln in text.splitlines() if ln.startswith("max_takeoff_mass_kg"))
    p = tmp_path / "m300.toml"
    p.write_text(text.replace(line + "\n", ""))
    plain, sized = fa.drone(str(p)), fa.drone("dji-matrice-300-rtk")
    assert sized.datasheet["motor_efficiency"] > plain.datasheet["motor_efficiency"] + 0.02
    # the hover point itself (propeller, speed) does not depend on it
    assert sized.datasheet["hover_rad_s"] == pytest.approx(plain.datasheet["hover_rad_s"])


def test_motor_size_laws_follow_their_published_motor_set():
    from pytest_flockai.airframe import motor_law as law
    # each reference motor's datasheet Rm and I0 from its mass and Kv, within a factor of two;
    # the log scatter of the motor constant about the law is small (0.11 on this set)
    errs = []
    for name, kv, i0, rm, grams in law.REFERENCE_MOTORS:
        kv_si = kv * 2 * math.pi / 60
        pred = law.winding_resistance(grams / 1000, kv_si)
        assert 0.5 < pred / rm < 2.0, name
        errs.append(math.log(pred / rm) / 2)      # Rm ~ 1/Km^2: half the log error is Km's
        p0 = law.iron_loss_w(grams / 1000, kv_si * law.I0_TEST_V)
        assert 0.3 < p0 / (i0 * law.I0_TEST_V) < 3.0, name
    assert (sum(e * e for e in errs) / len(errs)) ** 0.5 < 0.15
    # larger motors of a line are relatively better than geometric similarity's m^(5/6)
    assert 5 / 6 < law.KM_EXP < 1.0
    # a motor outside the set: T-Motor F40 III 2400 Kv, 30.8 g, 42 mOhm (T-Motor specifications,
    # as quoted by cameracopter.es/index.php/es/articles-es/39-reviews-es/292-tmotorf40iii-es)
    assert law.winding_resistance(0.0308, 2400 * 2 * math.pi / 60) == pytest.approx(0.042, rel=0.3)


def test_iron_loss_rises_with_speed_as_steinmetz():
    from pytest_flockai.airframe import motor_law as law
    assert law.iron_loss_w(0.1, 800.0) / law.iron_loss_w(0.1, 200.0) == pytest.approx(4 ** 1.5)
    assert law.iron_loss_w(0.2, 500.0) > law.iron_loss_w(0.1, 500.0)


def test_overrides_of_a_datasheet_blueprint_are_derived_again(tmp_path):
    base = fa.drone("dji-air-2s")
    heavy = fa.drone("dji-air-2s", mass_kg=0.7)
    assert heavy.airframe.mass_kg == 0.7 and heavy.payload_kg == 0.0
    # the hover point, the propeller's Reynolds number and the motors sized for 0.7 kg follow
    d0, d1 = base.datasheet, heavy.datasheet
    assert d1["hover_rad_s"] == pytest.approx(d0["hover_rad_s"] * math.sqrt(0.7 / 0.595), rel=0.03)
    assert d1["reynolds_075"] > d0["reynolds_075"]
    assert heavy.energy.component("motors").motor_rm_ohm != base.energy.component("motors").motor_rm_ohm
    assert heavy.rotor.max_speed_rad_s > base.rotor.max_speed_rad_s
    # same as writing the value into the blueprint's [datasheet] table
    text = (BLUEPRINTS / "dji-air-2s.toml").read_text()
    assert "mass_kg = 0.595 " in text
    p = tmp_path / "air-700g.toml"
    p.write_text(text.replace("mass_kg = 0.595 ", "mass_kg = 0.7 "))
    assert d1 == fa.drone(str(p)).datasheet
    # the pack voltage sets the motor model (Kv from the design speed at that voltage)
    assert fa.drone("dji-air-2s", battery_v=12.0).datasheet["motor_kv_rpm_v"] < d0["motor_kv_rpm_v"]
    assert fa.drone("dji-air-2s", motor_kv=1100.0).datasheet["motor_kv_rpm_v"] == 1100.0
    assert fa.drone("dji-air-2s", datasheet__prop_pitch_in=4.5).datasheet["ct"] > d0["ct"]
    # a payload is the same drone carrying more: nothing derived again
    loaded = fa.drone("dji-air-2s", payload_kg=0.1)
    assert loaded.datasheet == d0 and loaded.mass_kg == pytest.approx(0.695)


def test_datasheet_overrides_refused_where_they_cannot_be_derived():
    with pytest.raises(ConfigError, match=r"prop_diameter_in=9\.0 is a \[datasheet\] field, and this "
                                          r"blueprint has no \[datasheet\] table"):
        fa.drone("dji-mavic-2-pro", prop_diameter_in=9.0)
    with pytest.raises(ConfigError, match="datasheet__mass_kg"):
        fa.drone("dji-mavic-2-pro", datasheet__mass_kg=1.0)
    with pytest.raises(ConfigError, match="unknown override 'datasheet__mas_kg'.*mass_kg"):
        fa.drone("dji-air-2s", datasheet__mas_kg=1.0)
    with pytest.raises(ConfigError, match=r"\[datasheet\]: mass_kg = -1\.0 .*allowed: > 0"):
        fa.drone("dji-air-2s", mass_kg=-1.0)
    # a fitted blueprint's mass_kg stays its airframe field
    assert fa.drone("dji-mavic-2-pro", mass_kg=1.0).airframe.mass_kg == 1.0


def test_a_datasheet_no_load_current_is_taken_at_its_test_voltage(tmp_path):
    # a maker's I0 is measured without load at a test voltage (10 V by default): at hover the
    # no-load current follows the iron-loss law, I0 ~ omega^0.5 (loss ~ omega^1.5 / EMF ~ omega)
    extra = "motor_kv = 1400.0\nmotor_rm_ohm = 0.3\nmotor_i0_a = 0.5\nprop_blades = 2 "
    d = fa.drone(str(_mini(tmp_path, **{"prop_blades = 2 ": extra})))
    kv = 1400.0 * 2 * math.pi / 60
    at_hover = 0.5 * math.sqrt(d.datasheet["hover_rad_s"] / (kv * 10.0))
    assert d.datasheet["motor_i0_a"] == pytest.approx(at_hover)
    m = d.energy.component("motors")
    assert (m.motor_i0_a, m.motor_i0_rad_s) == (pytest.approx(at_hover), d.datasheet["hover_rad_s"])
    d7 = fa.drone(str(_mini(tmp_path, **{"prop_blades = 2 ": "motor_i0_v = 7.4\n" + extra})))
    assert d7.datasheet["motor_i0_a"] == pytest.approx(at_hover * math.sqrt(10.0 / 7.4))


def test_section_drag_is_laminar_below_transition_and_turbulent_above():
    """Blasius (C_d ~ Re^-1/2) up to Re 1e5, turbulent skin friction (Re^-1/5) above: the
    two laws meet at the transition, and the drag keeps falling, more slowly, past it."""
    assert dsm.section_drag(dsm.RE_REF) == pytest.approx(dsm.CD_REF)
    assert dsm.section_drag(1.5e4) == pytest.approx(dsm.CD_REF * 2.0)      # (6e4 / 1.5e4)^0.5
    t = dsm.RE_TURBULENT
    assert dsm.section_drag(t * 0.999) == pytest.approx(dsm.section_drag(t * 1.001), rel=1e-3)
    assert dsm.section_drag(4 * t) == pytest.approx(dsm.section_drag(t) * 4 ** -0.2)
    # above the transition the laminar law would have given a lower drag
    assert dsm.section_drag(4 * t) > dsm.CD_REF * (4 * t / dsm.RE_REF) ** -0.5


def test_section_drag_takes_arrays():
    np = pytest.importorskip("numpy")
    re = np.array([1.5e4, 6e4, 4e5])
    out = dsm.section_drag(re, maximum=np.maximum)
    assert out.shape == (3,)
    assert list(out) == pytest.approx([dsm.section_drag(float(r)) for r in re])


def test_large_rotors_are_less_efficient_than_the_laminar_law_alone_says():
    # the 21 in rotor of a 15 kg hexacopter hovers at Re ~ 1.6e5, in the turbulent range
    ct, cp, fm, omega = dsm.hover_propeller(21 * IN, 7 * IN, 2, 15.5 * 9.81 / 6)
    re = 0.75 * omega * 0.5 * 21 * IN * dsm.CHORD_RATIO * 0.5 * 21 * IN / dsm.NU_SEA_LEVEL
    assert re > dsm.RE_TURBULENT
    laminar_cd = dsm.CD_REF * (re / dsm.RE_REF) ** dsm.CD_RE_EXP
    assert dsm.section_drag(re) > 1.1 * laminar_cd


@pytest.mark.parametrize("mass, fc, camera", [(0.080, 0.3, 1.5), (0.249, 1.0, 1.5), (0.907, 2.5, 2.0),
                                               (9.5, 2.5, 2.0)])
def test_avionics_by_class(mass, fc, camera):
    a = dsm.avionics(mass)
    assert a["flight_controller_w"] == fc
    assert a["sensors"]["camera"] == camera and a["sensors"]["video_link"] == 0.8
    total = a["flight_controller_w"] + a["io_w"] + sum(a["sensors"].values())
    assert 2.0 < total < 6.0


def test_a_datasheet_blueprint_gets_its_class_avionics_unless_it_gives_its_own(tmp_path):
    d = fa.drone("dji-mini-3-pro")
    proc = d.energy.component("proc")
    assert proc.component("fc").power_w == 1.0                         # sub-250 g class
    assert proc.component("sensors.video_link").power_w == 0.8
    text = (BLUEPRINTS / "dji-mini-3-pro.toml").read_text()
    own = tmp_path / "mini.toml"
    own.write_text(text.replace("[radio]", "[energy]\nflight_controller_w = 4.0\n\n[radio]"))
    d2 = fa.drone(str(own))
    assert d2.energy.component("proc.fc").power_w == 4.0
    assert "video_link" not in d2.energy.component("proc.sensors")


def test_a_brushed_coreless_blueprint_gets_the_measured_coreless_efficiency(tmp_path):
    """Toy drones on brushed coreless motors are outside the brushless size laws; their
    motor and drive efficiency is the one measured on the Crazyflie 2.0's coreless propulsion
    (Bitcraze's electrical power over Foerster's shaft power at hover: 3.06 / 6.50 W)."""
    assert dsm.CORELESS_EFFICIENCY == pytest.approx(3.06 / 6.50, abs=0.005)
    brushless = fa.drone("dji-mini-3-pro")
    coreless = fa.drone(str(_mini(tmp_path, **{"prop_blades = 2 ": 'motor_type = "brushed-coreless"\nprop_blades = 2 '})))
    m = coreless.energy.component("motors")
    assert m.motor_efficiency == dsm.CORELESS_EFFICIENCY and m.esc_efficiency == 1.0
    assert m.motor_kv_rpm_v is None                    # no DC motor model: a constant efficiency
    assert coreless.datasheet["motor_efficiency"] == dsm.CORELESS_EFFICIENCY
    assert coreless.datasheet["motor_kv_rpm_v"] is None and coreless.datasheet["motor_rm_ohm"] is None
    # the same airframe draws more in hover on coreless motors than on brushless ones
    hover = [fa.Mission(d, fa.pilots.Hover(altitude=3.0, duration=8.0), until=15.0, return_home=False).run()
             for d in (brushless, coreless)]
    p = [r.telemetry[r.telemetry.stage == "pilot"].power_w.iloc[-50:].mean() for r in hover]
    assert p[1] > 1.1 * p[0]
    tello = fa.drone("ryze-tello").energy.component("motors")
    assert tello.motor_efficiency == dsm.CORELESS_EFFICIENCY
