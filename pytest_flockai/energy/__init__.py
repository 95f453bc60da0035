"""Energy: a composable model E_total = E_motors + E_proc + E_comm.

See ``components.py`` for the component interface and the built-ins and
``model.py`` for the composition (inspect, replace, remove, add).
"""

from .components import (Component, Constant, HoverPower, Motors, RadioLinear,
                          RadioStates, SoC, Usage)
from .model import EnergyModel, Group

__all__ = ["Component", "Constant", "EnergyModel", "Group", "HoverPower", "Motors",
           "RadioLinear", "RadioStates", "SoC", "Usage"]
