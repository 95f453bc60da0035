"""Wind: a mean vector plus seeded turbulence after the Dryden model of MIL-F-8785C.

Low-altitude turbulence (MIL-F-8785C, sec. 3.7.2.3, below 1000 ft), with h the
height above ground in feet (at least 10 ft, the model's lower limit):

- vertical intensity sigma_w = 0.1 W20 (light turbulence), W20 the wind speed at
  20 ft, here the mean wind speed;
- horizontal intensities sigma_u = sigma_v = sigma_w / (0.177 + 0.000823 h)^0.4,
  1.7 to 1.9 sigma_w at 10 to 100 ft;
- length scales L_w = h, L_u = L_v = h / (0.177 + 0.000823 h)^1.2 (ft).

Each axis is a first-order (Ornstein-Uhlenbeck) process with the Dryden
correlation time L / V, V the speed at which the frozen turbulence is carried
past the drone (Taylor's hypothesis: the mean wind speed, at least 1 m/s).
That is Dryden's longitudinal filter exactly; the lateral and vertical ones
are second order in the specification and first order here. The intensities
and time constants follow the drone's height every tick, so the gusts grow
stronger and slower as it climbs.

``gust_std`` given: the horizontal intensity sigma_u (the vertical one keeps the
specification's ratio); ``gust_tau_s`` given: one fixed correlation time for all
three axes instead of the length scales. The aerodynamic force comes from the
drone's velocity relative to this air.
"""

from __future__ import annotations

import math
from numbers import Real
from typing import NamedTuple

import numpy as np

from .. import _check, limits
from .._xp import MATH
from ..clock import Clocked
from ..errors import ConfigError

FT = 0.3048


def dryden_low_altitude(h_m, xp=MATH):
    """(sigma_u / sigma_w, L_u (m), L_w (m)) of MIL-F-8785C at height h_m above ground."""
    h = xp.maximum(h_m / FT, 10.0)
    h = xp.minimum(h, 1000.0)
    k = 0.177 + 0.000823 * h
    return k ** -0.4, h / k ** 1.2 * FT, h * FT


def gust_intensities(h_m, sigma_w20, gust_std, gust_tau_s, carry_mps, xp=MATH):
    """(sigma_horizontal, sigma_vertical, tau_horizontal, tau_vertical) at height h_m;
    ``gust_std < 0``: the specification's intensities, ``gust_tau_s <= 0``: its length
    scales carried at ``carry_mps`` (``Wind.intensities`` with None as -1)."""
    ratio, lu, lw = dryden_low_altitude(h_m, xp)
    given = gust_std >= 0.0
    su = xp.where(given, gust_std, sigma_w20 * ratio)
    sw = xp.where(given, gust_std / ratio, sigma_w20)
    fixed = gust_tau_s > 0.0
    return su, sw, xp.where(fixed, gust_tau_s, lu / carry_mps), xp.where(fixed, gust_tau_s,
                                                                          lw / carry_mps)


def ou_coefficients(dt, su, sw, tu, tw, xp=MATH):
    """(a_h, b_h, a_v, b_v): one step g' = a g + b n of the exact OU discretisation."""
    ah, aw = xp.exp(-dt / tu), xp.exp(-dt / tw)
    return ah, su * xp.sqrt(1.0 - ah * ah), aw, sw * xp.sqrt(1.0 - aw * aw)


class WindParams(NamedTuple):
    """A wind as numbers (``Wind.batch_params``; -1 stands for None)."""

    mean: np.ndarray
    active: bool
    gust_std: float
    gust_tau_s: float
    sigma_w20: float
    carry_mps: float


class Wind:
    def __init__(self, mean=(0.0, 0.0, 0.0), *, gust_std: float | None = None,
                 gust_tau_s: float | None = None):
        self.mean = _check.vector("mean", mean, 3, where="Wind")
        speed = math.sqrt(sum(c * c for c in self.mean))
        self.sigma_w20 = 0.1 * speed            # MIL-F-8785C light: sigma_w = 0.1 W20
        limits.check_at_most(f"mean = {self.mean!r}: speed", speed, "MAX_WIND_MPS", where="Wind",
                             unit=" m/s")
        self.gust_std = (None if gust_std is None
                         else _check.non_negative("gust_std", gust_std, where="Wind"))
        if self.gust_std is not None:
            limits.check_at_most("gust_std", self.gust_std, "MAX_WIND_MPS", where="Wind",
                                 unit=" m/s")
        self.gust_tau_s = (None if gust_tau_s is None
                           else _check.positive("gust_tau_s", gust_tau_s, where="Wind"))
        self.carry_mps = max(1.0, speed)        # Taylor: turbulence carried past at the mean wind

    @property
    def turbulent(self) -> bool:
        return (self.gust_std if self.gust_std is not None else self.sigma_w20) > 0.0

    def intensities(self, h_m: float):
        """(sigma_horizontal, sigma_vertical, tau_horizontal, tau_vertical) at height h_m."""
        p = self.batch_params()
        return gust_intensities(h_m, p.sigma_w20, p.gust_std, p.gust_tau_s, p.carry_mps)

    def batch_params(self) -> WindParams:
        """This wind's numbers, for the shared formulas and the batched backend."""
        return WindParams(mean=np.asarray(self.mean, dtype=float), active=self.turbulent,
                          gust_std=-1.0 if self.gust_std is None else float(self.gust_std),
                          gust_tau_s=-1.0 if self.gust_tau_s is None else float(self.gust_tau_s),
                          sigma_w20=self.sigma_w20, carry_mps=self.carry_mps)

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
        return {"mean": list(self.mean), "gust_std": self.gust_std, "gust_tau_s": self.gust_tau_s,
                "turbulence": "MIL-F-8785C Dryden, low altitude"}

    def __repr__(self):
        g = "Dryden" if self.gust_std is None else f"{self.gust_std:g}"
        return f"Wind(mean={self.mean}, gust_std={g}, gust_tau_s={self.gust_tau_s})"

    def sampler(self, rng: np.random.Generator, dt: float) -> "WindSampler":
        return WindSampler(self, rng, dt)


class WindSampler:
    """Steps the turbulence on the simulated clock; draws in blocks (no per-tick
    allocation). Each axis: g' = a g + sigma sqrt(1 - a^2) n, a = exp(-dt / tau),
    the exact discretisation of the OU process; sigma and tau at the drone's height,
    recomputed when it has moved by more than 0.5 m."""

    BLOCK = 4096

    def __init__(self, wind: Wind, rng, dt: float):
        self.wind, self.dt = wind, dt
        self.mean = wind.mean
        self.rng = rng
        self.active = wind.turbulent
        self._h = None
        self._coef = (0.0, 0.0, 0.0, 0.0)
        self.g = [0.0, 0.0, 0.0]
        if self.active:
            su, sw, _, _ = wind.intensities(0.0)
            self.g = list(rng.standard_normal(3) * np.array([su, su, sw]))
        self._buf = []
        self._k = 0

    def _at(self, h: float):
        self._coef = ou_coefficients(self.dt, *self.wind.intensities(h))
        self._h = h

    def step(self, h: float = 0.0):
        """Advance one period at height h (m above ground); returns the wind (wx, wy, wz)."""
        m = self.mean
        if not self.active:
            return m
        if self._h is None or abs(h - self._h) > 0.5:
            self._at(h)
        k = self._k
        if k >= len(self._buf):
            self._buf = self.rng.standard_normal(3 * self.BLOCK).tolist()
            k = 0
        buf, g = self._buf, self.g
        ah, bh, aw, bw = self._coef
        g[0] = ah * g[0] + bh * buf[k]
        g[1] = ah * g[1] + bh * buf[k + 1]
        g[2] = aw * g[2] + bw * buf[k + 2]
        self._k = k + 3
        return (m[0] + g[0], m[1] + g[1], m[2] + g[2])


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
        w = self.sampler.step(self.st.q[2])
        self._mwind[0], self._mwind[1], self._mwind[2] = w
        self.st.w = w
