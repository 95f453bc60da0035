"""Turbulence per MIL-F-8785C / Dryden: horizontal and vertical
intensities and length scales by height, instead of the vertical intensity on
every axis with a fixed 2 s correlation time."""

import math

import numpy as np
import pytest

import pytest_flockai as fa
from pytest_flockai.world.wind import dryden_low_altitude


def test_low_altitude_scales_match_the_specification():
    ratio, lu, lw = dryden_low_altitude(100 * 0.3048)          # 100 ft
    assert ratio == pytest.approx(1 / 0.2593 ** 0.4, rel=1e-3)   # sigma_u / sigma_w = 1.716
    assert lu / 0.3048 == pytest.approx(100 / 0.2593 ** 1.2, rel=1e-3)   # 505 ft
    assert lw / 0.3048 == pytest.approx(100.0)
    assert dryden_low_altitude(0.0) == dryden_low_altitude(10 * 0.3048)   # the 10 ft floor


def _series(wind, h, n=200_000, dt=0.02, seed=0):
    s = wind.sampler(np.random.default_rng(seed), dt)
    return np.array([s.step(h) for _ in range(n)]) - np.array(wind.mean)


def test_horizontal_gusts_are_stronger_and_slower_than_vertical_ones():
    w = fa.Wind((8.0, 0.0, 0.0))            # light turbulence: sigma_w = 0.8 m/s
    h = 30.0
    g = _series(w, h)
    ratio, lu, lw = dryden_low_altitude(h)
    assert g[:, 2].std() == pytest.approx(0.8, rel=0.08)
    assert g[:, 0].std() == pytest.approx(0.8 * ratio, rel=0.15)    # long correlation: fewer samples
    assert g[:, 1].std() > 1.3 * g[:, 2].std()
    # correlation time L / V: the autocorrelation falls to 1/e after tau
    for axis, length in ((2, lw), (0, lu)):
        tau = length / 8.0
        lag = int(round(tau / 0.02))
        x = g[:, axis]
        rho = np.corrcoef(x[:-lag], x[lag:])[0, 1]
        assert rho == pytest.approx(math.exp(-1), abs=0.12), (axis, tau, rho)


def test_gusts_grow_with_height():
    w = fa.Wind((6.0, 0.0, 0.0))
    low, high = w.intensities(5.0), w.intensities(100.0)
    assert high[0] < low[0]                 # sigma_u/sigma_w falls towards 1 with height
    assert high[2] > low[2] and high[3] > low[3]   # and the length scales grow


def test_given_gust_std_is_the_horizontal_intensity_and_tau_fixes_the_time():
    w = fa.Wind((4.0, 0.0, 0.0), gust_std=1.5, gust_tau_s=2.0)
    su, sw, tu, tw = w.intensities(20.0)
    assert su == 1.5 and sw < su and tu == tw == 2.0
