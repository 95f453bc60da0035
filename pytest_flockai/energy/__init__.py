"""Energy: a composable model E_total = E_motors + E_proc + E_comm.

See ``components.py`` for the component interface and the built-ins, ``rotors.py``
for the rotors' power and ``model.py`` for the composition (inspect, replace, remove, add).
"""

from .components import Component, Constant, RadioLinear, RadioStates, SoC, Usage
from .rotors import HoverPower, Motors
from .tree import EnergyModel, Group

__all__ = ["Component", "Constant", "EnergyModel", "Group", "HoverPower", "Motors",
           "RadioLinear", "RadioStates", "SoC", "Usage"]
