"""Sensors: noise statistics, determinism, scheduling, custom sensors."""

import math

import mujoco
import numpy as np
import pytest

import pytest_flockai as fa
from pytest_flockai import ConfigError
from pytest_flockai.airframe.mjspec import build_spec
from pytest_flockai.mission import seed_sequence
from pytest_flockai.sensors import (
    GPS,
    IMU,
    Barometer,
    BatterySensor,
    Camera,
    Compass,
    CsvSensor,
    FunctionSensor,
    Rangefinder,
    Sensor,
    SensorSuite,
    TemperatureSensor,
)

N = 4000


@pytest.fixture(scope="module")
def model():
    d = fa.drone("dji-mavic-2-pro")
    spec = build_spec(d, None, physics_dt=0.002)
    m = spec.compile()
    return m


def _state(m, pos=(3.0, -2.0, 20.0), vel=(1.0, 2.0, -0.5), yaw=0.7, omega=(0.1, -0.2, 0.3)):
    d = mujoco.MjData(m)
    d.qpos[:3] = pos
    d.qpos[3:7] = (math.cos(yaw / 2), 0, 0, math.sin(yaw / 2))
    d.qvel[:3] = vel
    d.qvel[3:6] = omega
    mujoco.mj_forward(m, d)
    return d


def _reads(sensor, m, d, seed=0, n=N):
    sensor.bind(m, d, np.random.default_rng(seed))
    return np.array([sensor.read(0.0, d) for _ in range(n)])


def _stats_ok(x, mean, std):
    x = np.asarray(x, dtype=float).reshape(len(x), -1)
    mean = np.broadcast_to(np.asarray(mean, dtype=float), x.shape[1:])
    std = np.broadcast_to(np.asarray(std, dtype=float), x.shape[1:])
    n = len(x)
    assert np.all(np.abs(x.mean(axis=0) - mean) < 4 * std / math.sqrt(n) + 1e-12), x.mean(axis=0)
    assert np.allclose(x.std(axis=0), std, rtol=0.06, atol=1e-12), x.std(axis=0)


def test_gps_statistics(model):
    d = _state(model)
    x = _reads(GPS(pos_std=1.5, vel_std=0.1), model, d)
    _stats_ok(x, [3.0, -2.0, 20.0, 1.0, 2.0, -0.5], [1.5, 1.5, 2.25, 0.1, 0.1, 0.1])


def test_imu_statistics_gyro_bias_and_free_fall(model):
    d = _state(model, vel=(0, 0, 0))   # no thrust, no airspeed: free fall, accelerometer ~0
    imu = IMU(gyro_std=0.01, accel_std=0.05, gyro_bias_std=0.02)
    x = _reads(imu, model, d)
    assert np.all(imu.bias[:3] != 0) and np.all(imu.bias[3:] == 0)
    _stats_ok(x, np.r_[np.array([0.1, -0.2, 0.3]) + imu.bias[:3], 0, 0, 0],
              [0.01] * 3 + [0.05] * 3)
    # with airspeed the accelerometer feels the drag: R^T (a - g), a from MuJoCo
    d = _state(model)
    R = d.xmat[1].reshape(3, 3)
    f = R.T @ (d.qacc[:3] - model.opt.gravity)
    assert np.linalg.norm(f) > 0.01
    _stats_ok(_reads(IMU(gyro_bias_std=0, accel_std=0.05), model, d)[:, 3:], f, 0.05)
    # resting on the ground: specific force +g on body z
    d0 = mujoco.MjData(model)
    for _ in range(300):
        mujoco.mj_step(model, d0)
    a = IMU(gyro_std=0, accel_std=0, gyro_bias_std=0)
    a.bind(model, d0, np.random.default_rng(0))
    assert a.read(0, d0)[3:] == pytest.approx([0, 0, 9.81], abs=0.02)


def test_compass_barometer_statistics(model):
    d = _state(model, yaw=3.1)
    h = _reads(Compass(heading_std_deg=2.0), model, d)
    # wrapped around +-pi: unwrap about the true heading
    err = np.angle(np.exp(1j * (h - 3.1)))
    _stats_ok(err, 0.0, math.radians(2.0))
    assert np.all(np.abs(h) <= math.pi)
    baro = Barometer(noise_std=0.1, bias_std=0.0)
    d0 = _state(model, pos=(0, 0, 1.0))
    baro.bind(model, d0, np.random.default_rng(1))
    d0.qpos[2] = 31.0
    mujoco.mj_kinematics(model, d0)
    _stats_ok([baro.read(0, d0) for _ in range(N)], 30.0, 0.1)


def test_rangefinder_hits_ground_and_buildings(model):
    d = _state(model, pos=(0, 0, 8.0), yaw=0.0)
    r = _reads(Rangefinder(noise_std=0.05, rel_std=0.0), model, d)
    _stats_ok(r, 8.0, 0.05)
    d = _state(model, pos=(0, 0, 30.0))
    assert math.isinf(_one(Rangefinder(max_range=12.0), model, d))
    city = fa.World.urban(seed=2, people=0)
    spec = build_spec(fa.drone("dji-mavic-2-pro"), city, physics_dt=0.002)
    mc = spec.compile()
    cx, cy, hx, hy, h = city.buildings[0]
    dc = _state(mc, pos=(cx, cy, h + 5.0))
    assert _one(Rangefinder(noise_std=0, rel_std=0, max_range=100), mc, dc) == pytest.approx(5.0)


def _one(sensor, m, d):
    sensor.bind(m, d, np.random.default_rng(0))
    return sensor.read(0.0, d)


def test_noise_is_reproducible_from_the_mission_seed(model):
    def run(seed):
        d = _state(model)
        suite = SensorSuite([GPS(), IMU(), Compass(), Barometer(),
                             TemperatureSensor(rate_hz=5.0)])
        suite.bind(model, d, seed_sequence(seed, "sensors"))
        out = []
        for k in range(300):
            suite.step(k * 0.01, d)
            out.append(np.r_[suite.latest["gps"], suite.latest["imu"], suite.latest["compass"],
                             suite.latest["barometer"], suite.latest["temperature"]])
        return np.array(out)
    a, b, c = run(5), run(5), run(6)
    assert np.array_equal(a, b)
    assert not np.allclose(a, c)
    # adding a sensor does not change another's noise (streams keyed by name)
    d = _state(model)
    s1 = SensorSuite([GPS()])
    s2 = SensorSuite([Compass(), GPS()])
    s1.bind(model, d, seed_sequence(5, "sensors"))
    s2.bind(model, d, seed_sequence(5, "sensors"))
    s1.step(0.0, d)
    s2.step(0.0, d)
    assert np.array_equal(s1.latest["gps"], s2.latest["gps"])


def test_suite_schedules_at_each_rate_and_counts(model):
    d = _state(model)
    calls = []
    suite = SensorSuite([GPS(rate_hz=10), IMU(rate_hz=200), Compass(rate_hz=3.0),
                         FunctionSensor("tick", lambda t, data: calls.append(t) or t, rate_hz=4),
                         Camera(rate_hz=1.0)])
    suite.bind(model, d, 0)
    dt = 0.01                                          # a 100 Hz control loop for 10 s
    for k in range(1000):
        suite.step(k * dt, d)
    c = suite.counts
    assert c["gps"] == 100
    assert c["imu"] == 1000                            # at most one reading per tick
    assert c["compass"] == 30
    assert c["tick"] == 40 and calls[:3] == [0.0, 0.25, 0.5]
    assert c["camera"] == 0 and suite.latest["camera"] is None    # on demand only
    assert suite.power_w == pytest.approx(0.07 + 0.013 + 0.00025 + 0.9)
    # nothing due: step returns at once; _next is the earliest due time
    assert 9.99 < suite._next <= 10.0
    assert suite._due == pytest.approx([10.0, 9.995, 10.0, 10.0], abs=1e-6)


def test_suite_rejects_bad_sensors():
    with pytest.raises(ConfigError, match="used twice"):
        SensorSuite([GPS(), GPS()])
    with pytest.raises(ConfigError, match=r"sensors\[0\]"):
        SensorSuite(["gps"])
    with pytest.raises(ConfigError, match="'lidar' is not on the drone.*'gps'"):
        SensorSuite([GPS()])["lidar"]
    with pytest.raises(ConfigError, match="rate_hz"):
        GPS(rate_hz=0)
    with pytest.raises(ConfigError, match="pos_std"):
        GPS(pos_std=-1)
    with pytest.raises(ConfigError, match="body_name = 'uav'"):
        GPS(body_name="uav").bind(fa.World.empty() and _empty_model(), None,
                                  np.random.default_rng(0))


def _empty_model():
    spec = mujoco.MjSpec()
    spec.worldbody.add_body(name="drone").add_freejoint()
    spec.body("drone").add_geom(size=[0.1, 0, 0])
    return spec.compile()


def test_temperature_sensor_kernels():
    u = TemperatureSensor(range=(20, 32), dist="uniform")
    u.bind(None, None, np.random.default_rng(0))
    x = np.array([u.read(0, None) for _ in range(N)])
    assert x.min() >= 20 and x.max() <= 32
    _stats_ok(x, 26.0, 12 / math.sqrt(12))
    g = TemperatureSensor(range=(20, 32), dist="gaussian")
    g.bind(None, None, np.random.default_rng(0))
    x = np.array([g.read(0, None) for _ in range(N)])
    assert x.min() >= 20 and x.max() <= 32
    assert abs(x.mean() - 26) < 0.1 and x.std() == pytest.approx(2.0, rel=0.06)
    with pytest.raises(ConfigError, match="dist = 'normal'.*'gaussian', 'uniform'"):
        TemperatureSensor(dist="normal")
    with pytest.raises(ConfigError, match="range"):
        TemperatureSensor(range=(32, 20))


def test_csv_sensor_rows_times_and_loop(tmp_path):
    p = tmp_path / "log.csv"
    p.write_text("time,temp\n0.0,20\n1.0,21\n2.0,22\n")
    rows = CsvSensor(p, "temp")
    rows.bind(None, None, np.random.default_rng(0))
    assert [rows.read(k, None) for k in range(5)] == [20, 21, 22, 20, 21]
    once = CsvSensor(p, "temp", loop=False)
    once.bind(None, None, np.random.default_rng(0))
    assert [once.read(k, None) for k in range(5)] == [20, 21, 22, 22, 22]
    timed = CsvSensor(p, "temp", time_column="time")
    timed.bind(None, None, np.random.default_rng(0))
    assert [timed.read(t, None) for t in (0.0, 0.5, 1.0, 2.9, 3.0, 4.5)] == [20, 20, 21, 22, 20, 21]
    with pytest.raises(ConfigError, match="column = 'tmp'.*'time', 'temp'"):
        CsvSensor(p, "tmp")
    with pytest.raises(ConfigError, match="no such file"):
        CsvSensor(tmp_path / "none.csv", "temp")


def test_battery_and_function_sensors():
    soc = {"v": 0.8}
    b = BatterySensor(lambda: soc["v"])
    b.bind(None, None, np.random.default_rng(0))
    assert b.read(0, None) == 0.8
    soc["v"] = 0.5
    assert b.read(1, None) == 0.5
    nan = BatterySensor()
    nan.bind(None, None, np.random.default_rng(0))
    assert math.isnan(nan.read(0, None))
    with pytest.raises(ConfigError, match="source"):
        BatterySensor("full")
    f = FunctionSensor("noise", lambda t, data, rng: rng.normal(), rate_hz=2)
    f.bind(None, None, np.random.default_rng(3))
    assert f.read(0, None) == np.random.default_rng(3).normal()
    with pytest.raises(ConfigError, match="fn"):
        FunctionSensor("x", 3)

    class Wind(Sensor):
        def read(self, t, data):
            return self.rng.uniform(0, 5)
    w = Wind("anemometer", rate_hz=1.0, power_w=0.1)
    s = SensorSuite([w])
    s.bind(None, _Data(), 1)
    s.step(0.0, None)
    assert 0 <= s.latest["anemometer"] <= 5 and s.power_w == 0.1


class _Data:
    time = 0.0
