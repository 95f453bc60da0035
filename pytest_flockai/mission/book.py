"""The flight book: phases, distance, top speed and tracking error.

A clocked component at 50 Hz (or every tick when the control rate is slower).
It classifies what the drone is doing into a ``Phase`` (take-off, hover,
move, accelerating, landing, landed) in whole ticks, so the phase times add
up exactly to the flight time, and logs each phase change.
"""

from __future__ import annotations

import math
from math import sqrt

from ..clock import CLOCK_EPS, Clocked
from ..control.stages import LANDING, PILOT, TAKEOFF
from ..phases import PHASES, Phase

# plain ints on the hot path (IntEnum lookups cost more)
_TAKEOFF, _HOVER, _MOVE, _ACCEL, _LANDING, _LANDED = (int(p) for p in Phase)

HOVER_SPEED = 0.5        # m/s: below this an airborne drone is hovering
ACCEL_THRESHOLD = 0.5    # m/s^2: above this it is accelerating
ACCEL_SMOOTHING_S = 0.2  # s: time constant of the |dv/dt| filter
BOOK_PERIOD_S = 0.02     # s: 50 Hz, rounded down to whole control ticks


def book_period(ctrl_dt: float) -> float:
    return max(ctrl_dt, BOOK_PERIOD_S // ctrl_dt * ctrl_dt)


class FlightBook(Clocked):
    period_s: float     # 50 Hz in whole control ticks: never None here

    def __init__(self, state, events, ctrl_dt: float):
        self.st, self.events = state, events
        self.period_s = book_period(ctrl_dt)
        self.every_tick = self.period_s == ctrl_dt      # then its clock is the tick itself
        self._t_next = 0.0
        self.next_due = -CLOCK_EPS
        self._t_book = 0.0
        self._a = math.exp(-self.period_s / ACCEL_SMOOTHING_S)
        self._acc = 0.0
        self._pvx = self._pvy = self._pvz = 0.0
        self._last = -1
        self.phase_ticks = [0] * len(PHASES)
        self.distance_m = self.max_speed_mps = self.tracking_error_max_m = 0.0

    @property
    def phase_time(self) -> list:
        """Seconds spent in each phase, in ``PHASES`` order."""
        return [n * self.period_s for n in self.phase_ticks]

    def step(self, t: float) -> None:
        s = self.st
        bdt = t - self._t_book
        self._t_book = t
        if not self.every_tick:
            self.advance_clock()
        v = s.v
        vx, vy, vz = v[0], v[1], v[2]
        if s.airborne:
            speed = s.speed
            acc = self._acc
            if bdt > 0.0:
                dx, dy, dz = vx - self._pvx, vy - self._pvy, vz - self._pvz
                a = self._a
                self._acc = acc = a * acc + (1.0 - a) * sqrt(dx * dx + dy * dy + dz * dz) / bdt
            stage = s.stage
            if stage == TAKEOFF:
                phase = _TAKEOFF
            elif stage == LANDING:
                phase = _LANDING
            elif speed < HOVER_SPEED:
                phase = _HOVER
            elif acc > ACCEL_THRESHOLD:
                phase = _ACCEL
            else:
                phase = _MOVE
            self.phase_ticks[phase] += 1
            self.distance_m += speed * self.period_s
            if speed > self.max_speed_mps:
                self.max_speed_mps = speed
            if stage == PILOT:
                q, sp = s.q, s.sp
                ex, ey, ez = q[0] - sp[0], q[1] - sp[1], q[2] - sp[2]
                e = sqrt(ex * ex + ey * ey + ez * ez)
                if e > self.tracking_error_max_m:
                    self.tracking_error_max_m = e
        else:
            phase = _LANDED
        if phase != self._last:
            self.events.add(t, "phase", phase=PHASES[phase])
            self._last = phase
        s.phase = phase
        self._pvx, self._pvy, self._pvz = vx, vy, vz
