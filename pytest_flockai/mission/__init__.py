"""Missions: ``Mission(drone, pilot, ...).run() -> FlightResult``.

- ``mission.py``: the Mission (inputs, validation, ``run``);
- ``plan.py``: a Mission resolved into a frozen ``FlightPlan`` (every check);
- ``assemble.py``: the flight built from the plan: MuJoCo model, vehicle state,
  clocked components in stepping order (``Run``);
- ``loop.py``: the clock loop (components, then physics);
- ``state.py``: the vehicle state and event log the components share;
- ``book.py``: phases, distance, tracking; ``ending.py``: end conditions;
  ``probing.py``: probes on the clock; ``result.py``: the FlightResult.
"""

from ..phases import PHASES, STAGES, Phase, Stage
from .assemble import Run
from .mission import Mission
from .plan import SEEDS, UNTIL, FlightPlan, resolve, seed_sequence
from .state import EventLog, VehicleState

__all__ = ["PHASES", "SEEDS", "STAGES", "UNTIL", "EventLog", "FlightPlan", "Mission", "Phase",
           "Run", "Stage", "VehicleState", "resolve", "seed_sequence"]
