"""Fleets: several drones in one mission, one world, one MuJoCo model, one clock.

A fleet flies in the same flight loop as a single Mission (``mission.assemble``
builds the one model and each drone's components, ``mission.loop`` flies 1..N
drones); this package holds only what is fleet-specific:

- ``fleet.py``: ``Fleet`` and ``FleetDrone`` (inputs, validation, ``run``);
- ``result.py``: the ``FleetResult`` and the fleet KPIs (separation measured in flight);
- ``offload.py``: remote inference on one ground station over a shared channel
  (the offload's and the remote tasks');
- ``areas.py``: a survey area split into one zig-zag strip per drone.
"""

from .areas import strips, survey
from .fleet import MAX_DRONES, PAD_CLEARANCE_M, Fleet, FleetDrone
from .fleet_result import FleetResult
from .offload import Offload

__all__ = ["MAX_DRONES", "PAD_CLEARANCE_M", "Fleet", "FleetDrone", "FleetResult", "Offload", "strips", "survey"]
