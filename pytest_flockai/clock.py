"""The one interface of everything the flight loop steps: ``Clocked``.

A clocked component owns one concern of a flight (the stage machine, the
controller, the energy integrator, the task scheduler, the probes...). The
loop asks each, in order, whether it is due (``t >= next_due``: one float
comparison when it is not) and then calls ``step(t)``; after the last tick it
calls ``finish(t)``. A component holds references to what it reads and writes,
given when it is built (the vehicle's state, the event log, other components):
nothing is shared through module globals.

Your own component (a geofence, a payload drop, a fault injector) subclasses
``Clocked``, sets ``period_s`` (None: every control tick) and implements
``step``; ``bind(run)`` hands it the flight (``run.vehicle``: the drone's
state, ``run.data``: MuJoCo's ``MjData``, ``run.event(t, kind, **info)``,
``run.stop(reason)``). Pass it as ``Mission(components=[...])``; it runs after
the built-in components of a tick, before the end conditions.
"""

from __future__ import annotations

import math

#: s: tolerance of the sub-clocks against the summed physics time
CLOCK_EPS = 1e-6


class Clocked:
    """Base class of the flight loop's components (see the module docstring)."""

    #: s between steps; None steps every control tick
    period_s: float | None = None
    #: simulated time of the next step; the loop steps the component when t >= next_due
    next_due: float = -math.inf
    #: stepped every control tick without looking at next_due (set from period_s at bind)
    every_tick: bool = False

    def bind(self, run) -> None:
        """Called once before the flight with the run context; resets per-flight state."""
        self.next_due = -math.inf if self.period_s is None else 0.0 - CLOCK_EPS
        self.every_tick = self.period_s is None
        self._t_next = 0.0

    def step(self, t: float) -> None:  # pragma: no cover - interface
        """Do this component's work at simulated time ``t`` (s); called when due."""
        raise NotImplementedError

    def advance_clock(self) -> None:
        """Move ``next_due`` one period on (for subclasses with a ``period_s``)."""
        if self.period_s is not None:
            self._t_next += self.period_s
            self.next_due = self._t_next - CLOCK_EPS

    def finish(self, t: float) -> None:
        """Called once when the flight ends (also the final partial interval)."""

    def to_dict(self) -> dict:
        """JSON-ready description for the flight's scenario (type and period)."""
        return {"type": type(self).__name__, "period_s": self.period_s}
