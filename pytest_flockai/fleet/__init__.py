"""Fleets: several drones in one mission, one world, one MuJoCo model, one clock.

- ``fleet.py``: ``Fleet`` and ``FleetDrone`` (inputs, validation, ``run``);
- ``assemble.py``: the one MuJoCo model and each drone's components on its
  slice of the shared MjData;
- ``loop.py``: the fleet's clock loop, drone-on-drone crashes, separation;
- ``result.py``: the ``FleetResult`` and the fleet KPIs;
- ``offload.py``: remote inference on one ground station over a shared channel;
- ``areas.py``: a survey area split into one zig-zag strip per drone.
"""

from .areas import strips, survey
from .offload import Offload
from .fleet import MAX_DRONES, PAD_CLEARANCE_M, Fleet, FleetDrone
from .result import FleetResult

__all__ = ["MAX_DRONES", "PAD_CLEARANCE_M", "Fleet", "FleetDrone", "FleetResult", "Offload", "strips", "survey"]
