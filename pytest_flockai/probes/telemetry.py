"""The telemetry store: numpy rows written on the telemetry clock, turned into
one pandas DataFrame at the end of the flight.

Each row holds the state (position, velocity, attitude, body rates), the
setpoint, the wind, power and energy (total and per top component), battery
remaining, each rotor's thrust, the flight phase and the mission stage; the
readings of the polled sensors and the navigation estimate are sampled at the
same rows. The rows live in fixed-size chunks (``CHUNK_ROWS``): a new chunk
is allocated when one is full, never per tick, and nothing is allocated for
time not yet flown, whatever ``until`` says.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from ..clock import CLOCK_EPS, Clocked
from ..phases import PHASES, STAGES, Phase

LANDED = int(Phase.LANDED)
#: rows per telemetry chunk (at 10 Hz, 15 minutes of flight; about 1 MB)
CHUNK_ROWS = 9000

BASE_COLS = ("x", "y", "z", "vx", "vy", "vz", "roll", "pitch", "yaw", "wx", "wy", "wz",
             "sp_x", "sp_y", "sp_z", "wind_x", "wind_y", "wind_z", "power_w", "energy_j",
             "battery_remaining")


class TelemetryRecorder:
    def __init__(self, rows: int, n_rotors: int, meter, data, suite=None, estimator=None):
        self.meter, self.data, self.suite, self.estimator = meter, data, suite, estimator
        polled = ([sn.name for sn in suite.sensors if not getattr(sn, "on_demand", False)]
                  if suite is not None else [])
        self._sensor_hist: dict[str, list] | None = {n: [] for n in polled} if polled else None
        self._est_hist: list = []
        self.columns = list(BASE_COLS) + [f"thrust_{i}" for i in range(n_rotors)] + \
            [f"energy_{k}_j" for k in ("motors", "proc", "comm")] + ["battery_v", "battery_a"]
        self._chunk = max(16, min(int(rows), CHUNK_ROWS))
        self._full: list = []        # filled chunks: (buf, t, phase, stage)
        self._new_chunk()
        self.n = 0

    def _new_chunk(self):
        k, cols = self._chunk, len(self.columns)
        self._buf, self._t = np.empty((k, cols)), np.empty(k)
        self._phase, self._stage = np.empty(k, dtype=np.int8), np.empty(k, dtype=np.int8)
        self._i = 0

    def record(self, t, q, v, sp, w, phase, stage, power, energy_j, e_usable):
        i = self._i
        if i >= self._chunk:          # chunk full: keep it, start a new one
            self._full.append((self._buf, self._t, self._phase, self._stage))
            self._new_chunk()
            i = 0
        qw, qx, qy, qz = q[3], q[4], q[5], q[6]
        roll = math.atan2(2 * (qw * qx + qy * qz), 1 - 2 * (qx * qx + qy * qy))
        pitch = math.asin(max(-1.0, min(1.0, 2 * (qw * qy - qz * qx))))
        yaw = math.atan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz))
        by_top = self.meter.totals_by_top()
        em, ep, ec = by_top.get("motors", 0.0), by_top.get("proc", 0.0), by_top.get("comm", 0.0)
        self._buf[i] = (q[0], q[1], q[2], v[0], v[1], v[2], roll, pitch, yaw, v[3], v[4], v[5],
                        sp[0], sp[1], sp[2], w[0], w[1], w[2], power, energy_j,
                        max(0.0, 1.0 - energy_j / e_usable), *self.data.act.tolist(), em, ep, ec,
                        self.meter.battery.voltage_v, self.meter.battery.current_a)
        self._t[i] = t
        if self._sensor_hist is not None:
            latest = self.suite.latest
            for name, hist in self._sensor_hist.items():
                hist.append(latest.get(name))
            if self.estimator is not None and self.estimator.p is not None:
                self._est_hist.append(tuple(self.estimator.p))
        self._phase[i] = phase
        self._stage[i] = stage
        self._i = i + 1
        self.n += 1

    def last_t(self) -> float:
        """The time of the last row recorded (-inf before the first)."""
        if self._i:
            return float(self._t[self._i - 1])
        return float(self._full[-1][1][-1]) if self._full else -math.inf

    def frame(self) -> pd.DataFrame:
        """The DataFrame (index: simulated time ``t``), built once. Its rows are the first
        ``n`` recorded: a flight stopped by the wall-clock watchdog in the middle of
        ``record`` (``Overrun`` lands at any bytecode) leaves the chunks and the counters
        one step apart (a chunk kept but not yet renewed comes twice, after the rows
        counted), and ``n`` is the last thing ``record`` counts."""
        n, i = self.n, self._i
        parts = self._full + [(self._buf[:i], self._t[:i], self._phase[:i], self._stage[:i])]
        buf, ts, phase, stage = (np.concatenate([p[j] for p in parts])[:n] for j in range(4))
        tel = pd.DataFrame(buf, columns=self.columns, index=pd.Index(ts, name="t"), copy=False)
        tel["phase"] = pd.Categorical.from_codes(phase, categories=list(PHASES))
        tel["stage"] = pd.Categorical.from_codes(stage, categories=list(STAGES))
        self._sensor_columns(tel, n)
        return tel

    def _sensor_columns(self, tel, n):
        """Sensor readings as columns ``sensor.<name>`` (vectors: ``.0``, ``.1``...)."""
        if self._sensor_hist:
            for name, hist in self._sensor_hist.items():
                hist = hist[:n]
                first = next((r for r in hist if r is not None), None)
                try:
                    arr = np.asarray(first, dtype=float)
                except (TypeError, ValueError):
                    continue
                if arr.ndim == 0:
                    tel[f"sensor.{name}"] = [np.nan if r is None else float(r) for r in hist]
                elif arr.ndim == 1 and arr.size <= 16:
                    vals = np.full((len(hist), arr.size), np.nan)
                    for i, r in enumerate(hist):
                        if r is not None:
                            vals[i] = r
                    for j in range(arr.size):
                        tel[f"sensor.{name}.{j}"] = vals[:, j]
        if self._est_hist and len(self._est_hist) >= n:
            e = np.asarray(self._est_hist[:n])
            tel["est_x"], tel["est_y"], tel["est_z"] = e[:, 0], e[:, 1], e[:, 2]


class TelemetryStep(Clocked):
    """The telemetry recorder as a clocked component (``telemetry_hz``); ``finish``
    records the final state."""

    def __init__(self, recorder: TelemetryRecorder, state, data, hz: float):
        self.rec, self.st, self.data = recorder, state, data
        self.period_s = 1.0 / hz
        self._t_next = 0.0
        self.next_due = -CLOCK_EPS

    def step(self, t: float) -> None:
        self.advance_clock()
        s = self.st
        self.rec.record(t, s.q, s.v, s.sp, s.w, s.phase, s.stage, s.power, s.energy_j, s.e_usable)

    def finish(self, t: float) -> None:
        if t <= self.rec.last_t():          # a row at this time already (until=<seconds>)
            return
        s, d = self.st, self.data
        self.rec.record(t, d.qpos.tolist(), d.qvel.tolist(), s.sp, s.w,
                        s.phase if s.airborne else LANDED, s.stage, self.rec.meter.last_power,
                        s.energy_j, s.e_usable)
