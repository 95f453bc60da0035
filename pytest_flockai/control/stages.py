"""The mission's stage machine: take off, fly the pilot's plan, return home, land.

A clocked component (every control tick): it writes the setpoint and the
stage into the vehicle's state and logs each stage change. The trajectories
of the stages it flies itself (climb, return leg, descent) are trapezoidal
legs (``control.trajectory``); during ``pilot`` the pilot writes the setpoint.
"""

from __future__ import annotations

import math

from ..clock import Clocked
from ..phases import STAGES, Stage  # noqa: F401  (STAGES re-exported)
from .trajectory import Leg, Path

# plain ints on the hot path (IntEnum comparisons cost more)
TAKEOFF, PILOT, RETURN, LAND, DONE = (int(s) for s in Stage)

#: m/s: a drone on the ground (in contact) descending slower than this has landed
TOUCHDOWN_SPEED = 0.3
#: m: how far below the ground the descent leg aims, so the drone settles with contact
LANDING_OVERSHOOT = 0.5


class StageMachine(Clocked):
    """Stages of one vehicle. ``accel``: the trajectories' acceleration limit."""

    every_tick = True

    def __init__(self, state, pilot, events, data, *, accel: float, climb_speed: float,
                 descent_speed: float, return_home: bool):
        self.st, self.pilot, self.events, self.data = state, pilot, events, data
        self.accel = accel
        self.climb_speed, self.descent_speed = climb_speed, descent_speed
        self.return_home = return_home
        home = state.home
        state.stage = TAKEOFF
        state.sp[:] = [home[0], home[1], home[2], 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        self.path = Path([Leg(home, (home[0], home[1], float(pilot.altitude)), climb_speed, accel)])
        self.t_stage = 0.0
        self._pupdate = pilot.update
        events.add(0.0, "stage", stage="takeoff")

    def step(self, t: float) -> None:
        s = self.st
        stage = s.stage
        if stage == PILOT:
            qc, vc = s.qc, s.vc
            if self._pupdate(t, (qc[0], qc[1], qc[2], vc[0], vc[1], vc[2]), s.sp):
                self._after_pilot(t)
        elif stage != DONE:
            if self.path.fill(t - self.t_stage, s.sp):
                if stage == TAKEOFF:
                    self._start_pilot(t)
                elif stage == RETURN:
                    self._land(t)
        if s.stage == LAND and self.data.ncon > 0 and abs(s.v[2]) < TOUCHDOWN_SPEED:
            s.stage = DONE
            s.t_land = t
            s.end_reason = "landed"          # the flight ends after this tick
            self.events.add(t, "stage", stage="landed")

    def go_home(self, t: float) -> None:
        """Leave the pilot's plan now: return home (if away) and land."""
        self._after_pilot(t, force_home=True)

    # -- transitions -----------------------------------------------------------
    def _start_pilot(self, t):
        s = self.st
        s.stage = PILOT
        qc, vc = s.qc, s.vc
        # the pilot starts over the take-off point (the climb's setpoint), not where a wind
        # pushed the drone during the climb: an autopilot holds the pad's position
        sp = s.sp
        self.pilot.start(t, (sp[0], sp[1], qc[2]), self.accel)
        self.events.add(t, "stage", stage="pilot")
        self._pupdate(t, (qc[0], qc[1], qc[2], vc[0], vc[1], vc[2]), s.sp)

    def _after_pilot(self, t, force_home=False):
        s = self.st
        sp, home = s.sp, s.home
        here = (sp[0], sp[1], sp[2])
        home_air = (home[0], home[1], sp[2])
        if (self.return_home or force_home) and math.dist(here[:2], home_air[:2]) > 0.5:
            self.events.add(t, "stage", stage="return")
            speed = getattr(self.pilot, "speed", 5.0)
            s.stage, self.t_stage = RETURN, t
            self.path = Path([Leg(here, home_air, speed, self.accel)])
            return
        self._land(t)

    def _land(self, t):
        """The one landing leg: straight down from the setpoint, below the ground."""
        s = self.st
        sp = s.sp
        here = (sp[0], sp[1], sp[2])
        s.stage, self.t_stage = LAND, t
        self.path = Path([Leg(here, (here[0], here[1], s.home[2] - LANDING_OVERSHOOT),
                              self.descent_speed, self.accel)])
        self.events.add(t, "stage", stage="landing")
