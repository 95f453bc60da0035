"""The controller and the navigation estimate as clocked components (every tick).

``Navigation`` sets what the pilot and the controller fly on: the truth, or
the complementary-filter estimate from GPS and barometer (``fly_on="estimate"``).
``Control`` runs the cascaded controller on it and writes the rotor commands
into MuJoCo's ``ctrl``; on the ground after landing it switches the motors off.
"""

from __future__ import annotations

from ..clock import Clocked
from ..errors import SimulationError
from .stages import DONE, STAGES


class Navigation(Clocked):
    """Flying on estimates: replaces the truth the loop put in ``qc, vc``."""

    every_tick = True

    def __init__(self, state, estimator, suite):
        self.st, self.estimator, self.suite = state, estimator, suite

    def step(self, t: float) -> None:
        s = self.st
        s.qc, s.vc = self.estimator.update(t, s.q, s.v, self.suite)


class Control(Clocked):
    every_tick = True

    def __init__(self, state, controller, data, n_rotors: int):
        self.st, self.controller, self.ctrl = state, controller, data.ctrl
        self._update = controller.update
        self._idx = range(n_rotors)

    def step(self, t: float) -> None:
        s = self.st
        if s.stage == DONE or not s.airborne:       # landed, or waiting on the pad
            self.ctrl[:] = 0.0
            s.airborne = False
            return
        f = self._update(s.qc, s.vc, s.sp)
        if f[0] != f[0]:
            raise SimulationError(
                f"the controller produced NaN rotor thrust at t = {t:.3f} s (stage "
                f"{STAGES[s.stage]}, setpoint {[round(x, 3) for x in s.sp]}); a pilot or "
                f"estimate gave a non-finite value")
        ctrl = self.ctrl
        for i in self._idx:
            ctrl[i] = f[i]
