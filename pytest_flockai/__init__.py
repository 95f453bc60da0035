"""pytest-flockai: test ML-driven drone applications with pytest.

The public API (see README.md): ``blueprints``, ``drone``, ``pilots``,
``Mission``, ``FlightResult``, ``World``, ``Wind``, ``devices`` and the errors.
"""

import os as _os
import sys as _sys


def _import_mujoco():
    """Import MuJoCo even when ``MUJOCO_GL`` names a GL backend that cannot load.

    MuJoCo loads the backend named by ``MUJOCO_GL`` at import time, and a
    missing library (say OSMesa) breaks the import itself, although physics
    needs no GL at all. Then MuJoCo is imported with GL disabled, the user's
    setting is kept, and the camera reports the problem when it is first used.
    """
    try:
        import mujoco  # noqa: F401
        return None
    except Exception as exc:
        gl = _os.environ.get("MUJOCO_GL", "")
        if not gl.strip():
            raise
        for name in [m for m in _sys.modules if m.split(".")[0] in ("mujoco", "OpenGL")]:
            del _sys.modules[name]
        saved_platform = _os.environ.pop("PYOPENGL_PLATFORM", None)
        _os.environ["MUJOCO_GL"] = "disable"
        try:
            import mujoco  # noqa: F401,F811
        finally:
            _os.environ["MUJOCO_GL"] = gl
            if saved_platform is not None:
                _os.environ["PYOPENGL_PLATFORM"] = saved_platform
        return f"MUJOCO_GL={gl!r} could not be loaded: {type(exc).__name__}: {exc}"


GL_IMPORT_ERROR = _import_mujoco()

from . import control as _control  # noqa: E402
from . import comm, kpis, limits, ml, probes, sensors
from .airframe import Drone, blueprints, drone
from .compute import devices
from .control import pilots
from . import policy
from .policy import Policy
from .world import actors
from .energy import EnergyModel
from .errors import ConfigError, FlockAIError, SimulationError
from .clock import Clocked
from .mission import Mission
from . import fleet
from .fleet import Fleet, FleetDrone, FleetResult
from .recording import recording
from .ml import Task
from .result import FlightResult
from .sensors import Conditions
from .sweeps import sweep
from .world import Atmosphere, Wind, World

__version__ = "0.1.0"

__all__ = ["Atmosphere", "Clocked", "Policy", "actors", "policy", "Conditions", "ConfigError", "Drone", "EnergyModel", "Fleet", "FleetDrone", "FleetResult", "FlightResult", "FlockAIError", "Mission",
           "SimulationError", "Task", "Wind", "World", "blueprints", "comm", "devices", "drone",
           "fleet", "kpis", "limits", "ml", "pilots", "probes", "recording", "sensors", "sweep",
           "__version__"]
del _control
