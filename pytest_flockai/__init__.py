"""pytest-flockai: test ML-driven drone applications with pytest.

The public API is ``__all__`` (see README.md and docs/reference/api.md):
``blueprints``, ``drone``, ``pilots``, ``Mission``, ``FlightResult``, ``World``,
``Wind``, ``devices``, the errors, and the public modules listed there.

Importing the package is cheap: the pytest plugin is loaded in every pytest run
of a project that installs it, also in runs that fly nothing. Only the errors,
the clock interface, the KPI table, the limits and the recording are imported
here; every other name (``fa.Mission``, ``fa.drone``, ``fa.pilots``...) and
every subpackage (``fa.world``, ``fa.energy``...) is imported on first use
(PEP 562 ``__getattr__``), with MuJoCo, pandas and the rest of the core behind
them. MuJoCo is imported through the GL guard of ``_mujoco.py``.
"""

from importlib import import_module as _import_module
from typing import TYPE_CHECKING

from . import kpis, limits
from .clock import Clocked
from .errors import ConfigError, FlockAIError, SimulationError
from .recording import recording

__version__ = "0.1.0"

if TYPE_CHECKING:      # what _LAZY imports on first use, spelled out for type checkers and docs
    from . import comm, fleet, ml, policy, probes, sensors

    # from .airframe.drone: airframe/ has submodules named drone and blueprints too
    from .airframe.drone import Drone, blueprints, drone
    from .compute import devices
    from .control import pilots
    from .energy import EnergyModel
    from .fleet import Fleet, FleetDrone, FleetResult
    from .mission import Mission
    from .ml import Task
    from .policy import Policy
    from .result import FlightResult
    from .sensors import Conditions
    from .sweeps import sweep
    from .world import Atmosphere, Wind, World, actors

#: public name -> (module, attribute in it; None: the module itself), imported on first use
_LAZY = {
    "Atmosphere": (".world", "Atmosphere"), "Wind": (".world", "Wind"),
    "World": (".world", "World"), "Conditions": (".sensors", "Conditions"),
    "Drone": (".airframe", "Drone"), "blueprints": (".airframe", "blueprints"),
    "drone": (".airframe", "drone"), "devices": (".compute", "devices"),
    "pilots": (".control.pilots", None), "EnergyModel": (".energy", "EnergyModel"),
    "Mission": (".mission", "Mission"), "Fleet": (".fleet", "Fleet"),
    "FleetDrone": (".fleet", "FleetDrone"), "FleetResult": (".fleet", "FleetResult"),
    "FlightResult": (".result", "FlightResult"), "Task": (".ml", "Task"),
    "sweep": (".sweeps", "sweep"), "GL_IMPORT_ERROR": ("._mujoco", "GL_IMPORT_ERROR"),
    "Policy": (".policy", "Policy"), "actors": (".world.actors", None),
}

#: the public face: these names, and in each public module listed here the names of its own
#: ``__all__`` (a module without one: its names without a leading underscore; a module there
#: is public in turn); everything else is internal and may move.
#: tests/test_public_api.py holds the docs, the examples and the API reference to it.
__all__ = ["Atmosphere", "Clocked", "Conditions", "ConfigError", "Drone", "EnergyModel", "Fleet",
           "FleetDrone", "FleetResult", "FlightResult", "FlockAIError", "Mission", "Policy",
           "actors", "policy",
           "SimulationError", "Task", "Wind", "World", "blueprints", "comm", "devices", "drone",
           "fleet", "kpis", "limits", "ml", "pilots", "probes", "recording", "sensors", "sweep",
           "budgets", "cache", "cli", "compute", "energy", "errors", "plots", "reports",
           "strategies", "sweeps", "world",
           "__version__"]


def __getattr__(name: str):
    """A public name or a subpackage, imported on first use (then kept as an attribute)."""
    module, attr = _LAZY.get(name, (f".{name}", None))
    if name.startswith("__"):
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    try:
        mod = _import_module(module, __name__)
    except ModuleNotFoundError as exc:
        if exc.name != f"{__name__}.{name}":
            raise
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
    value = mod if attr is None else getattr(mod, attr)
    globals()[name] = value
    return value


def __dir__() -> list:
    return sorted(set(globals()) | set(__all__) | set(_LAZY))
