"""When a flight ends on the battery or the clock: the last component of a tick.

The stage machine ends a flight that landed. This component ends it when the
battery is depleted (its usable charge is drawn, or the voltage under load
fell below the cut-off), sends the drone home to land when the battery falls to
its reserve (``until="battery_reserve"``), and ends it at the time limit
(``until`` seconds, or the mission's ``max_time_s`` cap). The energy used
changes only on the energy integrator's clock, so it runs on that clock (the
same grid) and, near the time limit, every tick.
"""

from __future__ import annotations

import time

from ..clock import CLOCK_EPS, Clocked
from ..control.stages import PILOT
from ..errors import SimulationError


class EndConditions(Clocked):
    period_s: float     # the energy integrator's period: never None here

    def __init__(self, state, events, stages, *, t_end: float, dt: float, timed: bool,
                 use_reserve: bool, reserve_j: float, energy_hz: float):
        self.st, self.events, self.stages = state, events, stages
        self.t_end, self.dt, self.timed = t_end, dt, timed
        self.use_reserve, self.reserve_j = use_reserve, reserve_j
        self.period_s = 1.0 / energy_hz
        self._t_next = self.period_s
        self.next_due = min(self._t_next - CLOCK_EPS, t_end - dt)

    def step(self, t: float) -> None:
        if t >= self._t_next - CLOCK_EPS:
            self._t_next += self.period_s
        self.next_due = min(self._t_next - CLOCK_EPS, self.t_end - self.dt)
        s = self.st
        if s.end_reason is not None:      # landed, or a user component stopped the flight
            return
        if s.energy_j >= s.e_usable or s.battery_cutoff:
            s.end_reason = "battery_depleted"
            self.events.add(t, "battery_depleted",
                            cause="cutoff_voltage" if s.battery_cutoff else "charge",
                            voltage_v=s.battery_v)
            return
        if self.use_reserve and s.stage == PILOT and s.e_usable - s.energy_j <= self.reserve_j:
            self.events.add(t, "battery_reserve", remaining=(s.e_usable - s.energy_j) / s.e_usable)
            self.stages.go_home(t)
        if t + 0.5 * self.dt >= self.t_end:
            s.end_reason = "time" if self.timed else "time_cap"


class WallClockGuard(Clocked):
    """Stops a flight that runs longer than ``max_wall_s`` seconds on the host
    (``Mission(max_wall_s=...)``): raises a ``SimulationError`` whose
    ``end_reason`` is ``"wall_time"``; ``Mission.run`` attaches the partial
    result. Looks at the host clock every 16th control tick; a call that never
    returns is interrupted at ``deadline`` by the loop's watchdog (``watchdog.py``)."""

    EVERY = 16

    def __init__(self, max_wall_s: float):
        self.max_wall_s = max_wall_s
        self.deadline = time.perf_counter() + max_wall_s     # the flight is being built now
        self._k = 0

    def bind(self, run) -> None:
        super().bind(run)
        self.every_tick = True

    def step(self, t: float) -> None:
        self._k += 1
        if self._k % self.EVERY:
            return
        if time.perf_counter() > self.deadline:
            exc = SimulationError(f"Mission: max_wall_s = {self.max_wall_s:g} s of host time "
                                  f"exceeded at t = {t:.3f} s simulated; the flight was stopped "
                                  f"(the partial result is on this error's .result)")
            exc.end_reason = "wall_time"
            raise exc
