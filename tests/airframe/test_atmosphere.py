"""The atmosphere: ICAO standard air at a field elevation, in the
physics (thrust limits, body drag) and in the energy model alike."""

import math

import pytest

import pytest_flockai as fa
from pytest_flockai.airframe.mjspec import build_model
from pytest_flockai.physics import RHO_SEA_LEVEL


def test_standard_atmosphere_matches_the_icao_table():
    sea = fa.Atmosphere(0.0)
    assert sea.density == pytest.approx(1.2250, abs=1e-4) and sea.temperature_c == pytest.approx(15.0)
    high = fa.Atmosphere(2000.0)            # ICAO Doc 7488: 79.50 kPa, 2.0 degC, 1.0066 kg/m^3
    assert high.pressure_pa == pytest.approx(79495, rel=5e-4)
    assert high.temperature_c == pytest.approx(2.0)
    assert high.density == pytest.approx(1.0066, abs=5e-4)
    hot = fa.Atmosphere(0.0, temperature_c=35.0)        # same pressure, warmer: thinner air
    assert hot.density == pytest.approx(1.2250 * 288.15 / 308.15, rel=1e-3)


def test_density_reaches_mujoco_drag_and_thrust_limits():
    d = fa.drone("dji-mavic-2-pro")
    rho = fa.Atmosphere(2000.0).density
    sea, high = build_model(d, physics_dt=0.002), build_model(d, physics_dt=0.002, rho=rho)
    assert sea.opt.density == pytest.approx(RHO_SEA_LEVEL) and high.opt.density == pytest.approx(rho)
    assert high.actuator_ctrlrange[0, 1] == pytest.approx(sea.actuator_ctrlrange[0, 1] * rho / RHO_SEA_LEVEL)


def _hover(atmosphere, blueprint="generic-hexa-680"):
    r = fa.Mission(fa.drone(blueprint), fa.pilots.Hover(10, 60), until=40.0,
                   atmosphere=atmosphere).run()
    return r, r.energy_breakdown["motors.induced"] / r.sim_time_s


def test_at_2000_m_induced_power_rises_by_the_root_density_ratio_and_payload_falls():
    """40 s hovering at 10 m on a blueprint with a constant motor efficiency (the hexa):
    induced power rises by sqrt(1.225 / 1.0066) = 1.103 at 2000 m, the total by less; the
    Mavic's largest payload (thrust-to-weight 1.3) falls from 0.84 kg to 0.53 kg. (On the
    Mavic's motor model the electrical induced share rises less, 1.08: its motors, sized for
    a thrust-to-weight of 2.5, work nearer their best load in thin air.)"""
    atm = fa.Atmosphere(2000.0)
    sea, p_sea = _hover(None)
    high, p_high = _hover(atm)
    assert high.kpis["crashed"] == 0 and high.kpis["tracking_error_max_m"] < 0.5
    assert p_high / p_sea == pytest.approx(math.sqrt(RHO_SEA_LEVEL / atm.density), rel=0.02)
    assert high.kpis["mean_power_w"] > 1.05 * sea.kpis["mean_power_w"]
    d = fa.drone("dji-mavic-2-pro")
    assert d.max_payload_kg(atm.density) < 0.7 * d.max_payload_kg()
    assert high.scenario["atmosphere"]["altitude_m"] == 2000.0


def test_a_payload_that_flies_at_sea_level_is_refused_where_the_air_is_thin():
    d = fa.drone("dji-mavic-2-pro", payload_kg=0.7)
    fa.Mission(d, fa.pilots.Hover(10, 1))                         # fine at sea level
    with pytest.raises(fa.ConfigError, match="thrust-to-weight in air of 0.8"):
        fa.Mission(d, fa.pilots.Hover(10, 1), atmosphere=fa.Atmosphere(4000.0))


@pytest.mark.parametrize("kwargs, field", [({"altitude_m": 20000}, "altitude_m"),
                                           ({"altitude_m": 0, "temperature_c": 90}, "temperature_c")])
def test_bad_atmosphere_is_refused(kwargs, field):
    with pytest.raises(fa.ConfigError, match=field):
        fa.Atmosphere(**kwargs)


def test_mission_atmosphere_must_be_an_atmosphere():
    with pytest.raises(fa.ConfigError, match="atmosphere"):
        fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(1, 1), atmosphere=2000)
