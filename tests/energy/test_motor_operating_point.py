"""Motor efficiency at each operating point: with a blueprint's motor
(Kv, Rm, I0) the energy model's Motors component computes each motor's electrical power
from the torque and speed of its rotor every tick, in hover, climb and cruise alike."""

import math

import pytest

import pytest_flockai as fa
from pytest_flockai import ConfigError
from pytest_flockai.airframe import datasheet as dsm
from pytest_flockai.energy import Motors, Usage


def _bound(drone, **overrides):
    m = drone.energy.component("motors")
    kw = {k: v for k, v in m.params().items() if k != "rho"}
    kw.update(overrides)
    comp = Motors("motors", **kw)
    comp.bind(drone)
    return comp


def _steady(comp, u):
    """Power once the warm-started induced-velocity iteration has converged (a held state)."""
    for _ in range(30):
        p = comp.power(u)
    return p


def _usage(drone, thrust_per_rotor, v_rel=(0.0, 0.0, 0.0)):
    u = Usage(drone.airframe.rotor_count)
    u.dt, u.airborne = 0.01, True
    u.thrust = [thrust_per_rotor] * drone.airframe.rotor_count
    u.v_rel_body = v_rel
    return u


def _shaft(comp, drone, u):
    """Mechanical power of the same tick: the constant-efficiency path with eta = 1."""
    plain = Motors("m", figure_of_merit=comp.figure_of_merit,
                   induced_power_factor=comp.induced_power_factor, motor_efficiency=1.0,
                   esc_efficiency=1.0, wake_interference=comp.wake_interference)
    plain.bind(drone)
    return _steady(plain, u)


def test_the_motor_model_reproduces_its_hover_efficiency():
    d = fa.drone("dji-air-2s")
    m = d.energy.component("motors")
    assert m.motor_kv_rpm_v == pytest.approx(d.datasheet["motor_kv_rpm_v"])
    hover = d.hover_thrust_per_rotor_n
    with_model = _steady(_bound(d), _usage(d, hover))
    constant = _steady(_bound(d, motor_kv_rpm_v=None, motor_rm_ohm=None, motor_i0_a=None,
                              motor_i0_rad_s=None), _usage(d, hover))
    # the same operating point the datasheet's hover efficiency was computed at
    assert with_model == pytest.approx(constant, rel=1e-6)


@pytest.mark.parametrize("load", [0.6, 1.0, 1.6])
def test_each_motor_follows_the_dc_motor_model_at_its_operating_point(load):
    d = fa.drone("dji-mini-3-pro")
    comp = _bound(d)
    t = load * d.hover_thrust_per_rotor_n
    u = _usage(d, t)
    shaft = _shaft(comp, d, u) / 4
    # by hand: omega from T = kf omega^2, Q = P / omega, I = Q Kv + I0 sqrt(omega / omega_0)
    kv = comp.motor_kv_rpm_v * math.pi / 30
    om = math.sqrt(t / d.rotor.thrust_coeff)
    q = shaft / om
    i0 = comp.motor_i0_a * math.sqrt(om / comp.motor_i0_rad_s)
    cur = q * kv + i0
    volts = om / kv + cur * comp.motor_rm_ohm
    assert _steady(comp, u) == pytest.approx(4 * volts * cur / comp.esc_efficiency, rel=1e-9)
    # and it agrees with the datasheet's own motor equation
    eta = dsm.motor_efficiency(q, om, kv_rad=kv, rm=comp.motor_rm_ohm, i0=i0)
    assert _steady(comp, u) == pytest.approx(4 * shaft / eta / comp.esc_efficiency, rel=1e-9)


def test_efficiency_changes_with_load_and_in_cruise():
    # the Mini's small motors lose mostly in their windings (I^2 Rm): lighter load, better
    # efficiency; a heavier one costs more than the mechanical power alone says
    d = fa.drone("dji-mini-3-pro")
    comp = _bound(d)
    hover = d.hover_thrust_per_rotor_n

    def eta(u):
        return _shaft(comp, d, u) / (_steady(comp, u) * comp.esc_efficiency)

    e_hover = eta(_usage(d, hover))
    assert e_hover == pytest.approx(d.datasheet["motor_efficiency"], rel=1e-6)
    assert eta(_usage(d, 0.7 * hover)) > e_hover > eta(_usage(d, 1.4 * hover))
    # cruise at 6 m/s (21.6 km/h): the disc tilted ~5 deg, translational lift lowers the
    # shaft power, and the motors at that lighter torque run more efficiently than at hover
    tilt = math.radians(5.0)
    cruise = _usage(d, hover / math.cos(tilt), v_rel=(6.0 * math.cos(tilt), 0.0, 6.0 * math.sin(tilt)))
    assert _shaft(comp, d, cruise) < _shaft(comp, d, _usage(d, hover))
    assert eta(cruise) > e_hover


def test_blueprints_without_a_motor_keep_their_constant_efficiency():
    d = fa.drone("generic-hexa-680")
    m = d.energy.component("motors")
    assert m.motor_kv_rpm_v is None and "motor_kv_rpm_v" not in m.params()
    comp = _bound(d)
    for load in (0.7, 1.0, 1.5):
        u = _usage(d, load * d.hover_thrust_per_rotor_n)
        assert _steady(comp, u) == pytest.approx(_shaft(comp, d, u) / (comp.motor_efficiency * comp.esc_efficiency),
                                             rel=1e-12)


def test_a_user_motor_efficiency_on_a_datasheet_blueprint_wins(tmp_path):
    from pathlib import Path
    text = (Path(fa.__file__).parent / "airframe" / "blueprints" / "dji-mini-3-pro.toml").read_text()
    p = tmp_path / "mini.toml"
    p.write_text(text.replace("\n[radio]\n", "\n[energy]\nmotor_efficiency = 0.9\n\n[radio]\n"))
    m = fa.drone(str(p)).energy.component("motors")
    assert m.motor_efficiency == 0.9 and m.motor_kv_rpm_v is None


def test_an_incomplete_motor_is_refused_naming_the_fields():
    with pytest.raises(ConfigError, match="motor_kv_rpm_v given without motor_i0_a, "
                                          "motor_i0_rad_s, motor_rm_ohm; allowed: all four"):
        Motors(figure_of_merit=0.6, motor_efficiency=0.7, esc_efficiency=0.95, motor_kv_rpm_v=900.0)
    with pytest.raises(ConfigError, match="motor_rm_ohm"):
        Motors(figure_of_merit=0.6, motor_efficiency=0.7, esc_efficiency=0.95, motor_kv_rpm_v=900.0,
               motor_rm_ohm=-1.0, motor_i0_a=0.1, motor_i0_rad_s=500.0)


def _mini_constant(tmp_path):
    """The Mini 3 Pro with its hover motor efficiency as a constant (no motor model)."""
    from pathlib import Path
    eta = fa.drone("dji-mini-3-pro").datasheet["motor_efficiency"]
    text = (Path(fa.__file__).parent / "airframe" / "blueprints" / "dji-mini-3-pro.toml").read_text()
    p = tmp_path / "mini-constant.toml"
    p.write_text(text.replace("\n[radio]\n", f"\n[energy]\nmotor_efficiency = {eta!r}\n\n[radio]\n"))
    return str(p)


def test_a_datasheet_drone_flies_on_the_motor_model(tmp_path):
    # hover with a payload: the motors' energy grows more than with a constant efficiency
    # (the copper loss grows as I^2, and the current with the torque)
    def motors_j(bp, payload):
        d = fa.drone(bp, payload_kg=payload)
        return fa.Mission(d, fa.pilots.Hover(altitude=3.0, duration=6.0)).run().kpis["energy_motors_j"]

    const = _mini_constant(tmp_path)
    assert fa.drone(const).energy.component("motors").motor_kv_rpm_v is None
    light, heavy = motors_j("dji-mini-3-pro", 0.0), motors_j("dji-mini-3-pro", 0.05)
    c_light, c_heavy = motors_j(const, 0.0), motors_j(const, 0.05)
    assert light == pytest.approx(c_light, rel=0.02)        # same hover efficiency
    assert heavy / light > c_heavy / c_light + 0.02


def test_a_payload_moves_the_motor_operating_point():
    """A payload raises each motor's thrust, speed and torque; on the Matrice 600
    Pro (motors sized for 15.5 kg) 6 kg more brings the motors nearer the load they are
    sized for: the electrical power rises less than the (m g)^1.5 of momentum theory over
    a constant efficiency would say, and more than the shaft power alone."""
    d = fa.drone("dji-matrice-600-pro")
    comp = _bound(d)
    m0, m1 = d.mass_kg, d.mass_kg + 6.0
    t0, t1 = (m * 9.81 / d.airframe.rotor_count for m in (m0, m1))
    p0, p1 = _steady(comp, _usage(d, t0)), _steady(comp, _usage(d, t1))
    s0, s1 = _shaft(comp, d, _usage(d, t0)), _shaft(comp, d, _usage(d, t1))
    assert s1 / s0 == pytest.approx((m1 / m0) ** 1.5, rel=0.01)         # momentum theory
    eta0, eta1 = s0 / p0, s1 / p1
    assert eta1 != pytest.approx(eta0, rel=1e-3)                           # a new operating point
    assert p1 / p0 == pytest.approx((s1 / s0) * (eta0 / eta1), rel=1e-9)
    # the rotor turns faster: omega ~ sqrt(T)
    assert math.sqrt(t1 / d.rotor.thrust_coeff) / math.sqrt(t0 / d.rotor.thrust_coeff) == pytest.approx(
        math.sqrt(m1 / m0))


def test_a_payload_shortens_the_flight_more_than_in_proportion_to_the_mass():
    d0 = fa.drone("dji-matrice-100")
    d1 = fa.drone("dji-matrice-100", payload_kg=1.0)
    p = []
    for d in (d0, d1):
        comp = _bound(d)
        p.append(_steady(comp, _usage(d, d.mass_kg * 9.81 / 4)))
    assert p[1] / p[0] > d1.mass_kg / d0.mass_kg
