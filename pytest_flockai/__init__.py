"""pytest-flockai: test ML-driven drone applications with pytest.

The public API (see DESIGN.md): ``blueprints``, ``drone``, ``pilots``,
``Mission``, ``FlightResult``, ``World``, ``Wind``, ``devices`` and the errors.
"""

from . import control as _control
from . import comm, kpis, ml, probes, sensors
from .airframe import Drone, blueprints, drone
from .compute import devices
from .control import pilots
from .energy import EnergyModel
from .errors import ConfigError, FlockAIError, SimulationError
from .mission import Mission
from .ml import Task
from .result import FlightResult
from .world import Wind, World

__version__ = "0.1.0"

__all__ = ["ConfigError", "Drone", "EnergyModel", "FlightResult", "FlockAIError", "Mission",
           "SimulationError", "Task", "Wind", "World", "blueprints", "devices", "drone", "comm", "kpis", "ml", "pilots", "probes", "sensors",
           "__version__"]
del _control
