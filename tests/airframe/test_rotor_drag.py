"""Rotor drag, the H-force: airframe/rotor_drag.py in the physics, the
datasheet's top-speed balance and the energy model's profile power."""

import math

import numpy as np
import pytest

import pytest_flockai as fa
from pytest_flockai.airframe import datasheet
from pytest_flockai.airframe.rotor_drag import BLADE_DRAG_DEFAULT, h_force
from pytest_flockai.control.stages import PILOT
from pytest_flockai.energy.components import Usage
from pytest_flockai.physics import RHO_SEA_LEVEL, G


class Record(fa.Clocked):
    """Each tick in the pilot stage: the applied force (world), the rotors' thrusts and
    the drone's state (runs after the built-in components, so this tick's force)."""

    def bind(self, run):
        super().bind(run)
        self.run, self.rows = run, []
        a0 = run.model.actuator("rotor0").id
        ad = int(run.model.actuator_actadr[a0])
        self.act = run.data.act[ad:ad + run.plan.drone.airframe.rotor_count]
        self.xfrc = run.data.xfrc_applied[run.model.body("drone").id]

    def step(self, t):
        s = self.run.vehicle
        if s.stage == PILOT:
            self.rows.append((t, list(self.xfrc[:3]), list(self.act), list(s.v[:3]),
                              list(s.q[3:7]), tuple(s.w), s.stage))


def _fly(drone, pilot, until, wind=None):
    rec = Record()
    fa.Mission(drone, pilot, wind=wind, seed=0, until=until, components=[rec]).run()
    return rec.rows


def _rot(q):
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _formula(drone, act, v_rel_world, q):
    """Sum over rotors of the H-force formula, translation only (the rotation's share
    omega x r is negligible in steady flight), in the world frame."""
    R = _rot(q)
    vb = R.T @ np.asarray(v_rel_world)
    vpar = math.hypot(vb[0], vb[1])
    mag = sum(h_force(drone.rotor.blade_drag, drone.rotor.diameter_m, drone.rotor.thrust_coeff,
                      RHO_SEA_LEVEL, T, vpar) for T in act)
    return R @ (-mag * np.array([vb[0], vb[1], 0.0]) / vpar)


def test_constant_speed_in_still_air_feels_the_h_force_of_the_formula():
    d = fa.drone("dji-mavic-2-pro")
    rows = _fly(d, fa.pilots.Waypoints([(400.0, 0.0, 20.0)], speed=12.0), until=45.0)
    cruise = [r for r in rows if abs(math.hypot(*r[3][:2]) - 12.0) < 0.05]
    assert len(cruise) > 200
    for t, f, act, v, q, _w, _ in cruise[::50]:
        want = _formula(d, act, v, q)
        assert np.allclose(f, want, rtol=0.02, atol=1e-3), (t, f, want)
    f = np.mean([r[1] for r in cruise], axis=0)
    # opposes the motion (+x), about 0.12 N for the Mavic at 12 m/s (body drag there: 2 N)
    assert f[0] < -0.1 and abs(f[1]) < 0.02 * abs(f[0])
    body = 0.5 * RHO_SEA_LEVEL * d.airframe.drag_area_m2[0] * 12.0 ** 2
    assert 0.03 * body < -f[0] < 0.5 * body


def test_the_h_force_tilts_the_drone_further_at_the_same_speed():
    pitches = []
    for bd in (0.0, BLADE_DRAG_DEFAULT):
        d = fa.drone("dji-mavic-2-pro", blade_drag=bd)
        rows = _fly(d, fa.pilots.Waypoints([(400.0, 0.0, 20.0)], speed=12.0), until=45.0)
        cruise = [r for r in rows if abs(math.hypot(*r[3][:2]) - 12.0) < 0.05]
        pitches.append(np.mean([math.asin(_rot(r[4])[0, 2]) for r in cruise]))
    # thrust tilt: tan(pitch) = (body drag + H) / (m g); H adds about 6 % to the body drag
    assert pitches[1] > pitches[0] * 1.03


def test_hovering_in_a_steady_wind_the_h_force_points_downwind():
    d = fa.drone("dji-mavic-2-pro")
    rows = _fly(d, fa.pilots.Hover(10, 30), until=25.0,
                wind=fa.Wind(mean=(0.0, 8.0, 0.0), gust_std=0.0))   # blowing towards +y
    held = [r for r in rows if r[0] > 15.0 and r[6] == PILOT]
    assert len(held) > 100
    for t, f, act, v, q, w, _ in held[::50]:
        want = _formula(d, act, np.subtract(v, w), q)
        assert np.allclose(f, want, rtol=0.02, atol=1e-3), (t, f, want)
        assert f[1] > 0.05 and abs(f[0]) < 0.05 * f[1]      # ~0.08 N at 8 m/s


def test_no_h_force_hovering_in_still_air():
    d = fa.drone("dji-mavic-2-pro")
    rows = _fly(d, fa.pilots.Hover(10, 20), until=20.0)
    held = [r for r in rows if r[0] > 10.0 and r[6] == PILOT]
    assert len(held) > 100
    assert max(math.hypot(*r[1][:2]) for r in held) < 1e-4 * d.mass_kg * G


def test_datasheet_drag_areas_close_the_top_speed_balance_with_the_h_force():
    d = fa.drone("dji-mavic-2-pro-datasheet")
    ds = d.datasheet
    t = math.radians(datasheet.TOP_TILT_DEG)
    v = 20.0                          # the blueprint's top speed, 72 km/h
    n, T = 4, d.mass_kg * G / 4 / math.cos(t)
    h = n * h_force(d.rotor.blade_drag, d.rotor.diameter_m, d.rotor.thrust_coeff, RHO_SEA_LEVEL,
                    T, v * math.cos(t))
    ax, _, az = d.airframe.drag_area_m2
    seen = math.hypot(ax * math.cos(t), az * math.sin(t))
    assert d.mass_kg * G * math.tan(t) == pytest.approx(0.5 * RHO_SEA_LEVEL * seen * v * v
                                                       + h * math.cos(t), rel=1e-6)
    assert ds["blade_drag"] == d.rotor.blade_drag > 0.0
    # without the rotors' share the body would need more drag area
    assert seen < 2 * d.mass_kg * G * math.tan(t) / (RHO_SEA_LEVEL * v * v)


def test_the_energy_model_does_not_count_the_h_force_work_twice():
    """The profile power's mu^2 term less exactly H V_par: the tilt's T V_ax pays for H."""
    d0, d1 = fa.drone("crazyflie-2-1", blade_drag=0.0), fa.drone("crazyflie-2-1")
    T, vpar = d1.hover_thrust_per_rotor_n, 10.0
    u = Usage(4)
    u.v_rel_body, u.thrust, u.airborne = (vpar, 0.0, 0.0), [T] * 4, True
    parts = []
    for d in (d0, d1):
        m = d.energy.component("motors")
        m.bind(d)
        parts.append(m.power_parts(u)[1] * m.motor_efficiency * m.esc_efficiency)
    h = h_force(d1.rotor.blade_drag, d1.rotor.diameter_m, d1.rotor.thrust_coeff, RHO_SEA_LEVEL,
                T, vpar)
    assert parts[0] - parts[1] == pytest.approx(4 * h * vpar, rel=1e-9)


def test_blade_drag_out_of_range_names_the_field():
    with pytest.raises(fa.ConfigError, match="blade_drag"):
        fa.drone("dji-mavic-2-pro", blade_drag=-0.01)


@pytest.mark.parametrize("name", ["dji-mini-3-pro", "dji-mavic-2-pro-datasheet", "dji-matrice-600-pro"])
def test_blade_drag_follows_the_section_drag_at_the_hover_reynolds_number(name):
    """Sigma C_d0 of a datasheet rotor is its solidity times the section drag at
    its hover Reynolds number, laminar on a Mini (Re ~ 2.6e4), turbulent on the Matrice 600
    Pro's 21 in rotor (Re ~ 1.6e5), where the H-force is larger than the laminar law gives."""
    d = fa.drone(name)
    ds = d.datasheet
    sigma = 2 * datasheet.CHORD_RATIO / math.pi
    assert d.rotor.blade_drag == pytest.approx(sigma * datasheet.section_drag(ds["reynolds_075"]))
    laminar = sigma * datasheet.CD_REF * (ds["reynolds_075"] / datasheet.RE_REF) ** -0.5
    if ds["reynolds_075"] > datasheet.RE_TURBULENT:
        assert d.rotor.blade_drag > 1.05 * laminar
    else:
        assert d.rotor.blade_drag == pytest.approx(laminar)
