"""Sensors in flight: Listing 2's custom sensor, flying on noisy estimates."""

import numpy as np
import pytest

import pytest_flockai as fa
from pytest_flockai.sensors import TemperatureSensor


def test_listing2_temperature_sensor_is_read_and_draws_power():
    d = fa.drone("dji-mavic-2-pro", battery_mah=4500)
    temp = TemperatureSensor(range=(20, 32), dist="gaussian", rate_hz=1.0)
    temp.power_w = 0.5
    d.add_sensor(temp)
    r = fa.Mission(d, fa.pilots.Hover(5.0, 20.0), seed=1).run()
    col = r.telemetry["sensor.temperature"].dropna()
    assert len(col) > 100 and col.between(20, 32).all() and col.nunique() > 5
    assert r.energy_breakdown["proc.sensors.temperature"] == pytest.approx(0.5 * r.sim_time_s, rel=1e-6)
    base = fa.Mission(fa.drone("dji-mavic-2-pro", battery_mah=4500), fa.pilots.Hover(5.0, 20.0), seed=1).run()
    assert r.kpis["energy_proc_j"] == pytest.approx(base.kpis["energy_proc_j"] + 0.5 * r.sim_time_s, rel=1e-6)
    # the drone's own energy model is not changed by the flight
    assert "temperature" not in d.energy.component("proc.sensors")
    # same seed, same readings
    again = fa.Mission(d, fa.pilots.Hover(5.0, 20.0), seed=1).run()
    assert again.telemetry["sensor.temperature"].equals(r.telemetry["sensor.temperature"])


def test_add_sensor_rejects_duplicates_and_non_sensors():
    d = fa.drone("dji-mavic-2-pro")
    with pytest.raises(fa.ConfigError, match="already on the drone"):
        d.add_sensor(fa.sensors.GPS())          # the blueprint has a "gps"
    with pytest.raises(fa.ConfigError, match="expected a Sensor"):
        d.add_sensor("thermometer")


def test_flying_on_gps_and_baro_estimates():
    pilot = fa.pilots.ZigZag(area=((0, 0), (80, 40)), altitude=20, spacing=20, speed=6)
    truth = fa.Mission(fa.drone("dji-mavic-2-pro"), pilot, seed=4).run()
    est = fa.Mission(fa.drone("dji-mavic-2-pro"), pilot, seed=4, fly_on="estimate").run()
    assert est.end_reason == "landed" and est.kpis["crashed"] == 0
    tel = est.telemetry
    assert {"est_x", "sensor.gps.0", "sensor.barometer"} <= set(tel.columns)
    # navigation error: estimate vs truth stays within a few GPS sigmas
    err = np.hypot(tel.est_x - tel.x, tel.est_y - tel.y)
    assert err.max() < 3.0 and err.mean() < 1.5
    # flying on estimates tracks worse than on truth, but still lands near home
    assert est.kpis["tracking_error_max_m"] > truth.kpis["tracking_error_max_m"]
    last = tel.iloc[-1]
    assert np.hypot(last.x, last.y) < 4.0
    with pytest.raises(fa.ConfigError, match="fly_on"):
        fa.Mission(fa.drone("dji-mavic-2-pro"), pilot, fly_on="gps")
