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

# the one stage enum (phases.Stage), as plain ints under its member names on the hot path
# (IntEnum comparisons cost more)
TAKEOFF, PILOT, RETURN, LANDING, DONE = (int(Stage[n]) for n in ("TAKEOFF", "PILOT", "RETURN",
                                                                 "LANDING", "DONE"))

#: m/s: a drone on the ground (in contact) descending slower than this has landed
TOUCHDOWN_SPEED = 0.3
#: m: how far below the ground the descent leg aims, so the drone settles with contact
LANDING_OVERSHOOT = 0.5
#: a take-off whose climb leg is over with the drone below this share of the climb waits
#: ``CLIMB_GRACE_S`` more; still below it then, the flight ends "takeoff_failed" (blocked
#: by an obstacle above or around the pad, or too weak to lift off). A drone that climbs
#: is well above half way when its leg ends, so a normal flight never waits
CLIMB_FRACTION = 0.5
#: s: how long a slow climb may lag behind its leg before it counts as failed
CLIMB_GRACE_S = 10.0


def top_speed(drone, rho: float, g: float = 9.81) -> float:
    """m/s: the level speed in still air where the drag along the body's x axis equals
    the thrust's horizontal part at the tilt limit: sqrt(2 m g tan(tilt) / (rho CdA))
    (the relation the blueprints' drag areas were estimated from)."""
    af = drone.airframe
    mass = float(getattr(drone, "mass_kg", af.mass_kg))     # payload included
    return math.sqrt(2.0 * mass * g * math.tan(math.radians(af.max_tilt_deg))
                     / (rho * af.drag_area_m2[0]))


class StageMachine(Clocked):
    """Stages of one vehicle. ``accel``: the trajectories' acceleration limit.
    ``wait_on_ground`` (an app's autopilot, ``pytest_flockai.app``) keeps the drone on
    its pad, motors off, until ``take_off``; the default flight takes off at t = 0."""

    every_tick = True
    #: True while the drone waits on its pad for ``take_off`` (pre-flight)
    grounded = False

    def __init__(self, state, pilot, events, data, *, accel: float, climb_speed: float,
                 descent_speed: float, return_home: bool, top_speed: float | None = None):
        self.st, self.pilot, self.events, self.data = state, pilot, events, data
        self.accel = accel
        self.climb_speed, self.descent_speed = climb_speed, descent_speed
        self.return_home = return_home
        home = state.home
        state.stage = TAKEOFF
        state.sp[:] = [home[0], home[1], home[2], 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        self.path = Path([Leg(home, (home[0], home[1], float(pilot.altitude)), climb_speed, accel)])
        self.t_stage = 0.0
        self._t_climb_end = None                  # when the climb leg ended below half way
        self._pupdate = pilot.update
        events.add(0.0, "stage", stage="takeoff")
        asked = getattr(pilot, "speed", None)
        if top_speed is not None and asked is not None and asked > top_speed:
            events.add(0.0, "speed_capped", asked_mps=float(asked), top_mps=float(top_speed),
                       reason=f"the pilot asks {asked:g} m/s; the drone's drag at its tilt "
                              f"limit allows about {top_speed:.1f} m/s in still air")

    def step(self, t: float) -> None:
        s = self.st
        stage = s.stage
        if self.grounded:
            return
        if stage == PILOT:
            qc, vc = s.qc, s.vc
            if self._pupdate(t, (qc[0], qc[1], qc[2], vc[0], vc[1], vc[2]), s.sp):
                self._after_pilot(t)
        elif stage != DONE:
            if self.path.fill(t - self.t_stage, s.sp):
                if stage == TAKEOFF:
                    if self._climbed(t):
                        self._start_pilot(t)
                elif stage == RETURN:
                    self._land(t)
        if s.stage == LANDING and self.data.ncon > 0 and abs(s.v[2]) < TOUCHDOWN_SPEED:
            s.stage = DONE
            s.t_land = t
            s.end_reason = "landed"          # the flight ends after this tick
            self.events.add(t, "stage", stage="landed")

    def wait_on_ground(self, t: float) -> None:
        """Pre-flight: stay on the pad with the motors off until ``take_off``."""
        self.grounded = True
        self.st.airborne = False
        first = {"t": 0.0, "kind": "stage", "stage": "takeoff"}
        if t == 0.0 and first in self.events.items:     # the take-off comes when commanded
            self.events.items.remove(first)
        self.events.add(t, "preflight")

    def take_off(self, t: float, altitude: float) -> None:
        """End the pre-flight: climb from the pad to ``altitude`` (m, world z), then fly
        the pilot (its ``altitude`` becomes this one)."""
        s, home = self.st, self.st.home
        self.grounded = False
        s.airborne = True
        self.pilot.altitude = float(altitude)
        s.stage, self.t_stage = TAKEOFF, t
        self._t_climb_end = None
        self.path = Path([Leg(home, (home[0], home[1], float(altitude)), self.climb_speed,
                              self.accel)])
        self.events.add(t, "stage", stage="takeoff")

    def go_home(self, t: float) -> None:
        """Leave the pilot's plan now: return home (if away) and land."""
        self._after_pilot(t, force_home=True)

    def replace_pilot(self, t: float, pilot) -> None:
        """Fly ``pilot`` from now on, from where the drone is (a policy's new plan; during
        the pilot stage, or on the way home: then the pilot stage starts again)."""
        qc = self.st.qc
        if self.st.stage in (RETURN, TAKEOFF) and not self.grounded:
            self.st.stage = PILOT
            self.events.add(t, "stage", stage="pilot")
        self.pilot, self._pupdate = pilot, pilot.update
        pilot.start(t, (qc[0], qc[1], qc[2]), self.accel)

    def land_here(self, t: float) -> None:
        """Leave the plan now and land straight down."""
        self._land(t)

    def _climbed(self, t) -> bool:
        """Whether the drone rose enough to start the pilot's plan; ends the flight
        "takeoff_failed" once it lagged ``CLIMB_GRACE_S`` past its climb leg."""
        s = self.st
        home_z, target = s.home[2], float(self.pilot.altitude)
        climbed = s.qc[2] - home_z
        if climbed >= CLIMB_FRACTION * (target - home_z):
            return True
        if self._t_climb_end is None:
            self._t_climb_end = t
        elif t - self._t_climb_end >= CLIMB_GRACE_S:
            s.stage = DONE
            s.end_reason = "takeoff_failed"
            self.events.add(t, "takeoff_failed", climbed_m=float(climbed),
                            target_m=float(target - home_z), contacts=int(self.data.ncon),
                            reason=f"rose {climbed:.2f} m of {target - home_z:.2f} m in "
                                   f"{t:.1f} s: blocked (an obstacle above or around the "
                                   f"pad) or too weak to lift off")
        return False

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
        s.stage, self.t_stage = LANDING, t
        self.path = Path([Leg(here, (here[0], here[1], s.home[2] - LANDING_OVERSHOOT),
                              self.descent_speed, self.accel)])
        self.events.add(t, "stage", stage="landing")
