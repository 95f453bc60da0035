"""Custom data sources: random kernels (the paper's TempSensor) and CSV replay."""

from __future__ import annotations

import math
import os

import numpy as np
import pandas as pd

from .. import _check
from ..errors import ConfigError
from .base import Sensor

DISTS = ("gaussian", "uniform")


class TemperatureSensor(Sensor):
    """A random temperature reading (deg C), as the paper's Listing 2 ``TempSensor``.

    range: (low, high). dist "uniform": uniform in [low, high]; "gaussian":
    normal with mean (low + high) / 2 and standard deviation (high - low) / 6
    (the range is +-3 sigma), clipped to the range.
    """

    def __init__(self, range=(20.0, 32.0), dist: str = "gaussian", rate_hz: float = 1.0, *,
                 name: str = "temperature", power_w: float = 0.0):
        super().__init__(name, rate_hz=rate_hz, power_w=power_w)
        w = f"TemperatureSensor {name!r}"
        lo, hi = _check.vector("range", range, 2, where=w)
        if not lo < hi:
            raise ConfigError(f"{w}: range = {range!r} is not allowed; expected (low, high) "
                              f"with low < high")
        self.range = (lo, hi)
        self.dist = _check.choice("dist", dist, DISTS, where=w)

    def read(self, t, data):
        lo, hi = self.range
        if self.dist == "uniform":
            return float(self.rng.uniform(lo, hi))
        v = 0.5 * (lo + hi) + (hi - lo) / 6.0 * float(self.rng.standard_normal())
        return min(hi, max(lo, v))

    def to_dict(self):
        return {**super().to_dict(), "range": list(self.range), "dist": self.dist}


class CsvSensor(Sensor):
    """Replays a column of a CSV file (read once with pandas).

    time_column None: the k-th reading returns row k (rows at the sensor's
    rate). time_column given: the reading at t is the last row with time <= t
    (rows before the first time return the first row), times relative to the
    first row. loop: start again after the last row (with a time column the
    period is the span of the times plus one median step); otherwise keep
    returning the last row.
    """

    def __init__(self, path, column: str, time_column: str | None = None, loop: bool = True, *,
                 rate_hz: float = 1.0, name: str | None = None, power_w: float = 0.0):
        super().__init__(name or f"csv:{column}", rate_hz=rate_hz, power_w=power_w)
        w = f"CsvSensor {self.name!r}"
        p = os.fspath(path)
        if not os.path.isfile(p):
            raise ConfigError(f"{w}: path = {p!r}: no such file; expected a CSV file")
        try:
            df = pd.read_csv(p)
        except Exception as exc:
            raise ConfigError(f"{w}: path = {p!r} is not a readable CSV file: {exc}") from None
        for field, col in (("column", column), ("time_column", time_column)):
            if col is not None and col not in df.columns:
                raise ConfigError(f"{w}: {field} = {col!r} is not a column of {p!r}; allowed: "
                                  f"{', '.join(map(repr, df.columns))}")
        if len(df) == 0:
            raise ConfigError(f"{w}: path = {p!r} has no rows")
        try:
            self.values = df[column].to_numpy(dtype=float)
        except (TypeError, ValueError):
            raise ConfigError(f"{w}: column = {column!r} of {p!r} is not numeric") from None
        self.path, self.column, self.time_column, self.loop = p, column, time_column, bool(loop)
        self.times = None
        if time_column is not None:
            times = df[time_column].to_numpy(dtype=float)
            if not np.isfinite(times).all() or (np.diff(times) < 0).any():
                raise ConfigError(f"{w}: time_column = {time_column!r} of {p!r} must be finite "
                                  f"and non-decreasing")
            self.times = times - times[0]
            step = float(np.median(np.diff(self.times))) if len(times) > 1 else 1.0
            self.period = float(self.times[-1]) + (step if step > 0 else 1.0)
        self._k = 0

    def bind(self, model, data, rng):
        super().bind(model, data, rng)
        self._k = 0

    def read(self, t, data):
        n = len(self.values)
        if self.times is None:
            k = self._k
            self._k += 1
            k = k % n if self.loop else min(k, n - 1)
            return float(self.values[k])
        if self.loop:
            t = math.fmod(t, self.period)
        k = int(np.searchsorted(self.times, t, side="right")) - 1
        return float(self.values[min(max(k, 0), n - 1)])
