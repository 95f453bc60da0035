"""Navigation sensors: GPS, IMU, compass, barometer, rangefinder, battery.

They read the true state of the drone's body from ``MjData`` (body
``body_name``, "drone" by default) and add white Gaussian noise drawn from the
rng given to ``bind`` (the mission seed). The defaults come from public data
sheets, cited next to each number. Frames: world x east, y north, z up; body
x forward, y left, z up; yaw counter-clockwise from east (the telemetry
convention).

The IMU is computed from ``MjData`` (free-joint ``qvel`` and ``qacc``) at read
time rather than with MuJoCo gyro/accelerometer sensors: MuJoCo evaluates its
sensors at every physics step (the accelerometer forces an extra RNE pass),
about a million times a mission, for a reading the loop wants at most once per
control tick. The values are the same: angular velocity of the body in the
body frame, and specific force ``R^T (a - g)`` at the body origin (the centre
of mass: the airframe sets ``ipos = 0``), with ``a`` the acceleration of the
last physics substep.
"""

from __future__ import annotations

import math

import numpy as np

from .. import _check
from .._mujoco import mujoco
from ..errors import ConfigError
from .base import DroneBody, Sensor


class _BodySensor(Sensor):
    def __init__(self, name, *, rate_hz, power_w, body_name="drone"):
        super().__init__(name, rate_hz=rate_hz, power_w=power_w)
        if not isinstance(body_name, str) or not body_name:
            raise ConfigError(f"{type(self).__name__}: body_name = {body_name!r} is not allowed; "
                              f"expected the name of the drone's body")
        self.body_name = body_name
        self.body = None

    def bind(self, model, data, rng):
        super().bind(model, data, rng)
        self.body = DroneBody(model, self.body_name, f"{type(self).__name__} {self.name!r}")

    def _yaw(self, data) -> float:
        R = data.xmat[self.body.id]
        return math.atan2(R[3], R[0])


class GPS(_BodySensor):
    """Position and velocity in the world frame: ``array([x, y, z, vx, vy, vz])``.

    Defaults after the u-blox NEO-M8 data sheet (UBX-15031086): navigation
    update rate up to 10 Hz with concurrent GNSS; horizontal accuracy 2.5 m
    CEP (2.0 m with SBAS), velocity accuracy 0.05 m/s (50 %). A per-axis
    sigma s gives CEP = 1.18 s, so pos_std = 1.5 m is a CEP of 1.8 m (an
    SBAS-aided fix); vel_std = 0.1 m/s is conservative (0.05 m/s at 50 % is
    sigma = 0.074 m/s). GNSS altitude is worse than horizontal position:
    alt_std defaults to 1.5 x pos_std (an assumption; the data sheet gives no
    vertical figure). Power: 23 mA at 3.0 V continuous tracking (NEO-M8N data
    sheet) = 0.07 W. Errors are white (real GNSS errors are correlated over
    minutes).
    """

    def __init__(self, rate_hz: float = 10.0, pos_std: float = 1.5, vel_std: float = 0.1, *,
                 alt_std: float | None = None, name: str = "gps", power_w: float = 0.07,
                 body_name: str = "drone"):
        super().__init__(name, rate_hz=rate_hz, power_w=power_w, body_name=body_name)
        w = f"GPS {name!r}"
        self.pos_std = _check.non_negative("pos_std", pos_std, where=w)
        self.vel_std = _check.non_negative("vel_std", vel_std, where=w)
        self.alt_std = (1.5 * self.pos_std if alt_std is None
                        else _check.non_negative("alt_std", alt_std, where=w))
        self._std = np.array([self.pos_std, self.pos_std, self.alt_std,
                              self.vel_std, self.vel_std, self.vel_std])

    def read(self, t, data):
        b = self.body
        out = np.empty(6)
        out[:3] = data.xpos[b.id]
        out[3:] = data.qvel[b.qvel:b.qvel + 3]
        out += self.rng.standard_normal(6) * self._std
        return out


class IMU(_BodySensor):
    """Gyro and accelerometer in the body frame: ``array([gx, gy, gz, ax, ay, az])``.

    rad/s and m/s^2; at rest the accelerometer reads +9.81 on z (specific
    force). Defaults after the InvenSense MPU-6000 product specification
    (PS-MPU-6000A-00 rev 3.4): gyro total RMS noise 0.05 deg/s with the 100 Hz
    low-pass filter; accelerometer noise density 400 ug/sqrt(Hz), i.e.
    0.0039 m/s^2/sqrt(Hz) x sqrt(100 Hz) = 0.039 m/s^2 RMS. The gyro bias is
    drawn once per flight, N(0, gyro_bias_std) per axis: 0.005 rad/s
    (0.3 deg/s) is an assumed residual after start-up calibration (the raw
    zero-rate offset is up to +-20 deg/s). Power: 3.8 mA at 3.3 V = 0.013 W.
    """

    def __init__(self, rate_hz: float = 200.0, gyro_std: float = math.radians(0.05),
                 accel_std: float = 0.039, gyro_bias_std: float = 0.005, *,
                 accel_bias_std: float = 0.0, name: str = "imu", power_w: float = 0.013,
                 body_name: str = "drone"):
        super().__init__(name, rate_hz=rate_hz, power_w=power_w, body_name=body_name)
        w = f"IMU {name!r}"
        self.gyro_std = _check.non_negative("gyro_std", gyro_std, where=w)
        self.accel_std = _check.non_negative("accel_std", accel_std, where=w)
        self.gyro_bias_std = _check.non_negative("gyro_bias_std", gyro_bias_std, where=w)
        self.accel_bias_std = _check.non_negative("accel_bias_std", accel_bias_std, where=w)
        self._std = np.array([self.gyro_std] * 3 + [self.accel_std] * 3)
        self.bias = np.zeros(6)

    def bind(self, model, data, rng):
        super().bind(model, data, rng)
        self.bias = rng.standard_normal(6) * np.array([self.gyro_bias_std] * 3
                                                      + [self.accel_bias_std] * 3)
        self._g = np.array(model.opt.gravity)

    def read(self, t, data):
        b = self.body
        R = data.xmat[b.id].reshape(3, 3)
        out = np.empty(6)
        out[:3] = data.qvel[b.qvel + 3:b.qvel + 6]         # free joint: body-frame angular velocity
        out[3:] = R.T @ (data.qacc[b.qvel:b.qvel + 3] - self._g)
        out += self.bias + self.rng.standard_normal(6) * self._std
        return out


class Compass(_BodySensor):
    """Heading (rad, yaw counter-clockwise from east, wrapped to (-pi, pi]).

    Default noise after the Honeywell HMC5883L data sheet: "1 to 2 degree
    compass heading accuracy"; heading_std = 2 deg. Power: 100 uA at 2.5 V.
    """

    def __init__(self, rate_hz: float = 50.0, heading_std_deg: float = 2.0, *,
                 name: str = "compass", power_w: float = 0.00025, body_name: str = "drone"):
        super().__init__(name, rate_hz=rate_hz, power_w=power_w, body_name=body_name)
        self.heading_std = math.radians(_check.non_negative("heading_std_deg", heading_std_deg,
                                                            where=f"Compass {name!r}"))

    def read(self, t, data):
        h = self._yaw(data) + self.heading_std * float(self.rng.standard_normal())
        return math.atan2(math.sin(h), math.cos(h))


class Barometer(_BodySensor):
    """Altitude above the take-off point (m): the body's z at ``bind`` is zero.

    Defaults after the Bosch BMP280 data sheet (BST-BMP280-DS001): relative
    accuracy +-0.12 hPa = +-1 m; RMS noise 1.6 to 26 cm depending on
    oversampling and IIR filter (table 7; 2.4 cm for "handheld dynamic", 20.8 cm
    for "drop detection"): noise_std = 0.1 m, between the two, as prop wash
    adds pressure noise in flight. bias_std: a constant offset drawn once per
    flight (default 0: the altitude is zeroed at take-off). Power: 2.7 uA at
    1 Hz, 1.8 V; 0.001 W covers fast sampling.
    """

    def __init__(self, rate_hz: float = 50.0, noise_std: float = 0.1, *, bias_std: float = 0.0,
                 name: str = "barometer", power_w: float = 0.001, body_name: str = "drone"):
        super().__init__(name, rate_hz=rate_hz, power_w=power_w, body_name=body_name)
        w = f"Barometer {name!r}"
        self.noise_std = _check.non_negative("noise_std", noise_std, where=w)
        self.bias_std = _check.non_negative("bias_std", bias_std, where=w)

    def bind(self, model, data, rng):
        super().bind(model, data, rng)
        self.z0 = float(data.xpos[self.body.id][2])
        self.bias = self.bias_std * float(rng.standard_normal())

    def read(self, t, data):
        z = float(data.xpos[self.body.id][2]) - self.z0
        return z + self.bias + self.noise_std * float(self.rng.standard_normal())


class Rangefinder(_BodySensor):
    """Distance (m) along the body's -z axis to the first geom, by ``mujoco.mj_ray``.

    The ray starts at the body origin, ignores the drone's own geoms, and
    hits everything else (ground, buildings, people). No hit within
    ``max_range``: ``math.inf``. Defaults after the Benewake TFmini-S data
    sheet: range 0.1-12 m, accuracy +-6 cm below 6 m and +-1 % beyond:
    noise_std = max(0.04 m, 1 % of range) (taking the accuracy as 1.5 sigma);
    power <= 0.7 W (140 mA at 5 V).
    """

    def __init__(self, rate_hz: float = 50.0, max_range: float = 12.0, noise_std: float = 0.04, *,
                 rel_std: float = 0.01, min_range: float = 0.1, name: str = "rangefinder",
                 power_w: float = 0.7, body_name: str = "drone"):
        super().__init__(name, rate_hz=rate_hz, power_w=power_w, body_name=body_name)
        w = f"Rangefinder {name!r}"
        self.max_range = _check.positive("max_range", max_range, where=w)
        self.min_range = _check.number("min_range", min_range, where=w, minimum=0.0,
                                       maximum=self.max_range, max_inclusive=False)
        self.noise_std = _check.non_negative("noise_std", noise_std, where=w)
        self.rel_std = _check.non_negative("rel_std", rel_std, where=w)
        self._geomid = np.zeros(1, dtype=np.int32)

    def read(self, t, data):
        b = self.body
        R = data.xmat[b.id]
        down = np.array([-R[2], -R[5], -R[8]])
        dist = mujoco.mj_ray(self.model, data, data.xpos[b.id], down, None, 1, b.id, self._geomid)
        if dist < 0 or dist > self.max_range:
            return math.inf
        std = max(self.noise_std, self.rel_std * dist)
        return max(self.min_range, dist + std * float(self.rng.standard_normal()))


class BatterySensor(Sensor):
    """The battery's state as the mission knows it: ``source()`` or a value.

    source: a callable with no arguments, a number, or None: then, in a
    flight, the battery's remaining fraction (0..1) of that flight (the
    mission binds it anew for every flight; outside a flight it reads nan). The reading is the source's value plus
    N(0, noise_std). The quantity (state of charge 0..1, volts, ...) is
    whatever the source returns.
    """

    def __init__(self, source=None, rate_hz: float = 1.0, *, noise_std: float = 0.0,
                 name: str = "battery", power_w: float = 0.0):
        super().__init__(name, rate_hz=rate_hz, power_w=power_w)
        self.noise_std = _check.non_negative("noise_std", noise_std, where=f"BatterySensor {name!r}")
        self.source = source
        self._flight_source = None

    @property
    def source(self):
        """What the sensor reads: a callable with no arguments, a number, or None (the
        flight's own battery state)."""
        return self._source

    @source.setter
    def source(self, value):
        if value is not None and not callable(value):
            value = _check.number("source", value, where=f"BatterySensor {self.name!r}")
        self._source = value

    def bind_battery(self, source) -> None:
        """Per flight: the flight's own battery state, read when ``source`` is None."""
        self._flight_source = source

    def read(self, t, data):
        s = self._source if self._source is not None else self._flight_source
        v = math.nan if s is None else float(s() if callable(s) else s)
        if self.noise_std:
            v += self.noise_std * float(self.rng.standard_normal())
        return v
