"""Wind: a mean vector plus seeded gusts (Ornstein-Uhlenbeck per axis).

Each axis follows dw = -(w - mean) / tau dt + sigma sqrt(2 / tau) dW, so the
gust has standard deviation ``gust_std`` and correlation time ``gust_tau_s``.
The default gust_std is 10% of the mean speed: MIL-F-8785C gives light
low-altitude turbulence as sigma = 0.1 x the wind speed at 20 ft.
The aerodynamic force comes from the drone's velocity relative to this air.
"""

from __future__ import annotations

import math
from numbers import Real

import numpy as np

from .. import _check, limits
from ..clock import Clocked
from ..errors import ConfigError


class Wind:
    def __init__(self, mean=(0.0, 0.0, 0.0), *, gust_std: float | None = None, gust_tau_s: float = 2.0):
        self.mean = _check.vector("mean", mean, 3, where="Wind")
        speed = math.sqrt(sum(c * c for c in self.mean))
        limits.check_at_most(f"mean = {self.mean!r}: speed", speed, "MAX_WIND_MPS", where="Wind",
                             unit=" m/s")
        self.gust_std = (0.1 * speed if gust_std is None
                         else _check.non_negative("gust_std", gust_std, where="Wind"))
        limits.check_at_most("gust_std", self.gust_std, "MAX_WIND_MPS", where="Wind", unit=" m/s")
        self.gust_tau_s = _check.positive("gust_tau_s", gust_tau_s, where="Wind")

    @classmethod
    def coerce(cls, value) -> "Wind | None":
        if value is None or isinstance(value, Wind):
            return value
        if isinstance(value, Real) and not isinstance(value, bool):
            return cls((value, 0.0, 0.0))
        if isinstance(value, (str, bytes, dict)):
            raise ConfigError(f"wind = {value!r} is not allowed; expected None, a speed in m/s, "
                              f"(x, y, z) in m/s or fa.Wind(...)")
        return cls(value)

    def to_dict(self) -> dict:
        return {"mean": list(self.mean), "gust_std": self.gust_std, "gust_tau_s": self.gust_tau_s}

    def __repr__(self):
        return f"Wind(mean={self.mean}, gust_std={self.gust_std:g}, gust_tau_s={self.gust_tau_s:g})"

    def sampler(self, rng: np.random.Generator, dt: float) -> "WindSampler":
        return WindSampler(self, rng, dt)


class WindSampler:
    """Steps the gust process on the simulated clock; draws in blocks (no per-tick allocation)."""

    BLOCK = 4096

    def __init__(self, wind: Wind, rng, dt: float):
        self.mean = wind.mean
        self.a = math.exp(-dt / wind.gust_tau_s)
        self.b = wind.gust_std * math.sqrt(1.0 - self.a * self.a)   # exact OU discretisation
        self.rng = rng
        self.g = [0.0, 0.0, 0.0]
        if wind.gust_std > 0:
            self.g = list(rng.standard_normal(3) * wind.gust_std)
        self._buf = []
        self._k = 0
        self.active = wind.gust_std > 0

    def step(self):
        """Advance one period; returns the wind vector (wx, wy, wz)."""
        m = self.mean
        if not self.active:
            return m
        k = self._k
        if k >= len(self._buf):
            self._buf = self.rng.standard_normal(3 * self.BLOCK).tolist()
            k = 0
        buf, a, b, g = self._buf, self.a, self.b, self.g
        g[0] = a * g[0] + b * buf[k]
        g[1] = a * g[1] + b * buf[k + 1]
        g[2] = a * g[2] + b * buf[k + 2]
        self._k = k + 3
        return (m[0] + g[0], m[1] + g[1], m[2] + 0.5 * g[2])


class WindStep(Clocked):
    """The wind as a clocked component (every control tick): steps the gusts and
    sets MuJoCo's ``opt.wind``, against which MuJoCo applies body drag every
    substep; the vehicle state's ``w`` is the air velocity of this tick."""

    every_tick = True

    def __init__(self, wind: Wind, state, model, rng, dt: float):
        self.st = state
        self.sampler = wind.sampler(rng, dt)
        self._mwind = model.opt.wind
        self._mwind[:] = wind.mean

    def step(self, t: float) -> None:
        w = self.sampler.step()
        self._mwind[0], self._mwind[1], self._mwind[2] = w
        self.st.w = w
