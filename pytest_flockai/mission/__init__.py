"""Missions: ``Mission(drone, pilot, ...).run() -> FlightResult``, and the one
flight path of 1..N drones (a fleet flies through the same modules).

- ``mission.py``: the Mission (inputs, validation, ``run``);
- ``plan.py``: a Mission resolved into a frozen ``FlightPlan`` (every check);
- ``parts.py``: one factory each for the controller, the meter, the trajectories;
- ``assemble.py``: the flight built from the plans: one MuJoCo model, and per
  drone its vehicle state and clocked components in stepping order (``Run``);
- ``loop.py``: the clock loop of 1..N drones (components, then physics, contacts);
- ``state.py``: the vehicle state and event log the components share;
- ``book.py``: phases, distance, tracking; ``ending.py``: end conditions;
  ``probing.py``: probes on the clock; ``collect.py``: a drone's FlightResult.
"""

from ..phases import PHASES, STAGES, Phase, Stage
from .assemble import Flight, Run
from .mission import Mission
from .plan import SEEDS, UNTIL, FlightPlan, resolve, seed_sequence
from .state import EventLog, VehicleState

__all__ = ["PHASES", "SEEDS", "STAGES", "UNTIL", "EventLog", "Flight", "FlightPlan", "Mission", "Phase",
           "Run", "Stage", "VehicleState", "resolve", "seed_sequence"]
