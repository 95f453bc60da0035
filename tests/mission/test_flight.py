"""The flight core's must-shows."""

import math

import mujoco
import numpy as np
import pytest

import pytest_flockai as fa
from pytest_flockai import SimulationError
from pytest_flockai.airframe.mjspec import build_model
from pytest_flockai.physics import RHO_SEA_LEVEL


@pytest.fixture(scope="module")
def zigzag():
    pilot = fa.pilots.ZigZag(area=((0, 0), (100, 60)), altitude=30, spacing=20, speed=8)
    m = fa.Mission(fa.drone("dji-mavic-2-pro"), pilot, seed=1)
    return m, m.run()


def test_zigzag_flies_whole_pattern_and_lands_home(zigzag):
    m, r = zigzag
    k = r.kpis
    assert r.end_reason == "landed" and k["crashed"] == 0
    last = r.telemetry.iloc[-1]
    assert math.hypot(last.x, last.y) < 1.0
    assert last.z < 0.1
    # every corner of the pattern was visited (within 1.5 m)
    tel = r.telemetry
    for (x, y, z) in m.pilot.points:
        dmin = np.min(np.sqrt((tel.x - x) ** 2 + (tel.y - y) ** 2 + (tel.z - z) ** 2))
        assert dmin < 1.5, (x, y, z, dmin)
    assert k["tracking_error_max_m"] < 1.0


def test_zigzag_distance_matches_pattern_length(zigzag):
    m, r = zigzag
    k = r.kpis
    alt = m.pilot.altitude
    last_corner = m.pilot.points[-1]
    expected = alt + m.pilot.path_length + math.hypot(last_corner[0], last_corner[1]) + alt
    assert k["distance_m"] == pytest.approx(expected, rel=0.03)


def test_phase_times_add_up(zigzag):
    _, r = zigzag
    k = r.kpis
    parts = sum(k[n] for n in ("takeoff_time_s", "hover_time_s", "move_time_s", "accel_time_s",
                               "landing_time_s"))
    assert parts == pytest.approx(k["flight_time_s"], abs=0.05)
    assert k["max_speed_mps"] == pytest.approx(8.0, abs=0.6)
    assert set(r.telemetry.phase.unique()) >= {"takeoff", "move", "accelerating", "landing"}


def test_telemetry_columns_and_rate(zigzag):
    _, r = zigzag
    tel = r.telemetry
    for c in "x y z vx vy vz roll pitch yaw phase".split():
        assert c in tel.columns
    assert tel.index.name == "t"
    dt = np.diff(tel.index.values[:-1])
    assert np.allclose(dt, 0.1, atol=1e-6)    # 10 Hz by default


def test_to_dict_is_json_ready(zigzag):
    import json
    _, r = zigzag
    d = json.loads(json.dumps(r.to_dict()))
    assert d["scenario"]["pilot"]["type"] == "ZigZag" and d["scenario"]["seed"] == 1
    assert d["scenario"]["drone"]["name"] == "dji-mavic-2-pro"
    assert set(fa.kpis.names()) & set(d["kpis"]) >= {"flight_time_s", "energy_total_j"}


def _cf_hover(wind=None, seed=0, duration=20.0):
    return fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=duration),
                      wind=wind, seed=seed).run()


def test_crazyflie_hovers_within_5cm_still_air():
    r = _cf_hover()
    tel = r.telemetry
    held = tel[(tel.stage == "pilot") & (tel.index > tel[tel.stage == "pilot"].index[0] + 2.0)]
    assert len(held) > 100
    err = np.sqrt(held.x ** 2 + held.y ** 2 + (held.z - 1.0) ** 2)
    assert err.max() < 0.05
    assert r.kpis["crashed"] == 0 and r.end_reason == "landed"


def test_crazyflie_holds_position_in_5mps_wind_and_tilts_into_it():
    # gusts of 0.5 m/s horizontally (the default is MIL-F-8785C's light turbulence, 1 m/s
    # horizontally at 1 m for a 5 m/s wind); this test is about the mean wind
    r = _cf_hover(wind=fa.Wind((5.0, 0.0, 0.0), gust_std=0.5), duration=30.0)
    tel = r.telemetry
    t0 = tel[tel.stage == "pilot"].index[0]
    held = tel[(tel.stage == "pilot") & (tel.index > t0 + 5.0)]
    err = np.sqrt(held.x ** 2 + held.y ** 2 + (held.z - 1.0) ** 2)
    # 0.5 m before rotor drag was modelled: the H-force (airframe/rotor_drag.py) adds ~10 % to
    # the wind's force on the Crazyflie and the slow integral leaves it 0.41 m downwind
    # instead of 0.37 m (largest error 0.51 m, was 0.46 m); budget widened by 0.05 m
    assert err.max() < 0.55
    # wind blows towards +x: the drone pitches its nose down into the wind (-x side),
    # i.e. thrust tilted towards -x: negative pitch about y in our x-forward frame
    assert held.pitch.mean() < -0.05
    assert abs(held.roll.mean()) < 0.02


class StepPilot(fa.pilots.Pilot):
    """Holds (0, 0, 2) for 3 s, then jumps the setpoint 2 m east (no feed-forward)."""
    altitude = 2.0

    def start(self, t, position, accel):
        self.t0 = t

    def update(self, t, state, sp):
        sp[0] = 2.0 if t - self.t0 >= 3.0 else 0.0
        sp[1], sp[2] = 0.0, 2.0
        sp[3:10] = [0.0] * 7
        return t - self.t0 > 15.0


def test_position_step_settles_without_oscillation():
    r = fa.Mission(fa.drone("crazyflie-2-1"), StepPilot(), until=40.0).run()
    tel = r.telemetry
    t0 = tel[tel.stage == "pilot"].index[0] + 3.0
    after = tel[(tel.index >= t0) & (tel.stage == "pilot")]
    overshoot = after.x.max() - 2.0
    assert overshoot < 0.05 * 2.0, overshoot
    # settles into +-2 % of the step and stays there
    outside = after[(after.x - 2.0).abs() > 0.04]
    settle = outside.index.max() - t0
    assert settle < 8.0, settle
    # no oscillation: x never falls back once within 2 %
    crossings = np.sum(np.diff(np.sign(after.x.values - 2.0)) != 0)
    assert crossings <= 2


def test_same_seed_same_result_and_seeds_differ_with_wind():
    w = fa.Wind((3.0, 1.0, 0.0), gust_std=1.0)
    a = _cf_hover(wind=w, seed=7, duration=5.0)
    b = _cf_hover(wind=w, seed=7, duration=5.0)
    c = _cf_hover(wind=w, seed=8, duration=5.0)
    assert a.kpis == b.kpis
    assert a.telemetry.equals(b.telemetry)
    assert not a.telemetry[["x", "y"]].equals(c.telemetry[["x", "y"]])


class NaNPilot(fa.pilots.Pilot):
    altitude = 1.0

    def update(self, t, state, sp):
        sp[:] = [float("nan")] * 10
        return False


def test_nan_ends_with_clear_error_not_a_hang():
    with pytest.raises(SimulationError, match="NaN rotor thrust.*non-finite") as e:
        fa.Mission(fa.drone("crazyflie-2-1"), NaNPilot(), until=30.0).run()
    assert e.value.result.kpis["flight_time_s"] >= 0     # KPIs still reported


def test_crash_is_reported_with_kpis():
    # fly into the ground: waypoint below ground level is refused, so dive from altitude
    class Dive(fa.pilots.Pilot):
        altitude = 20.0

        def update(self, t, state, sp):
            sp[0], sp[1], sp[2] = 0.0, 0.0, -50.0
            sp[3:9] = [0.0, 0.0, -15.0, 0.0, 0.0, 0.0]
            sp[9] = 0.0
            return False
    r = fa.Mission(fa.drone("dji-mavic-2-pro"), Dive(), until=120.0).run()
    assert r.kpis["crashed"] == 1 and r.end_reason == "crashed"
    assert any(e["kind"] == "crash" for e in r.events)
    assert r.kpis["energy_total_j"] > 0 and r.kpis["flight_time_s"] > 0


def test_mission_argument_validation():
    d = fa.drone("crazyflie-2-1")
    p = fa.pilots.Hover(1.0, 1.0)
    with pytest.raises(fa.ConfigError, match="until"):
        fa.Mission(d, p, until="forever")
    with pytest.raises(fa.ConfigError, match="seed"):
        fa.Mission(d, p, seed=-1)
    with pytest.raises(fa.ConfigError, match="Pilot"):
        fa.Mission(d, "zigzag")


def test_orbit_and_hexacopter_fly():
    r = fa.Mission(fa.drone("generic-hexa-680"),
                   fa.pilots.Orbit(center=(0, 0), radius=15, altitude=20, speed=5, laps=1)).run()
    assert r.end_reason == "landed" and r.kpis["crashed"] == 0
    tel = r.telemetry
    circ = tel[(tel.stage == "pilot")]
    rad = np.sqrt(circ.x ** 2 + circ.y ** 2)
    assert rad.max() == pytest.approx(15, abs=1.0)
    # a slow 3.5 kg frame (60 ms motors) lags more while spinning up on the circle
    assert r.kpis["tracking_error_max_m"] < 1.5


def test_the_same_mission_flown_twice_is_identical():
    """Pilots and wind carry state during a flight; flying the same Mission object
    again starts from scratch."""
    m = fa.Mission(fa.drone("crazyflie-2-1"),
                   fa.pilots.Waypoints([(1.0, 0.0, 1.0), (1.0, 1.0, 1.0)], speed=1.0, loop=True),
                   wind=fa.Wind((2.0, 0.0, 0.0), gust_std=0.5), until=15.0, seed=3)
    a, b = m.run(), m.run()
    assert a.kpis == b.kpis and a.telemetry.equals(b.telemetry)


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_body_drag_is_half_rho_cda_v_squared_along_each_axis(axis):
    """airframe/mjspec.py: MuJoCo's ellipsoid fluid model, set up so the drag along
    each body axis is 1/2 rho (Cd A) |v| v with the blueprint's Cd*A."""
    d = fa.drone("dji-mavic-2-pro")
    m = build_model(d, None, physics_dt=0.002)
    data = mujoco.MjData(m)
    data.qpos[2] = 30.0
    data.qvel[axis] = 10.0
    mujoco.mj_forward(m, data)
    want = -0.5 * RHO_SEA_LEVEL * d.airframe.drag_area_m2[axis] * 10.0 ** 2
    assert data.qfrc_passive[axis] == pytest.approx(want, rel=1e-6)


def test_a_mujoco_reset_ends_the_flight_with_a_clear_error_not_a_hang(monkeypatch):
    """wind = 1e6 m/s: MuJoCo resets the state in every step (time stays near 0);
    the flight must end with a SimulationError naming the warning, carrying a result.
    (Such a wind is refused up front by limits.MAX_WIND_MPS; the limit is raised here.)"""
    monkeypatch.setattr(fa.limits, "MAX_WIND_MPS", 1e7)
    m = fa.Mission(fa.drone("dji-mavic-2-pro"), fa.pilots.Hover(10, 5), wind=1e6)
    with pytest.raises(SimulationError, match="MuJoCo reset the simulation.*mjWARN_BADQACC") as exc:
        m.run()
    assert exc.value.result.end_reason == "diverged"
