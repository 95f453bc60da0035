"""Moved to ``pytest_flockai.control.clocked``; the old path warns once per name
(``_deprecation.py``) and will be removed."""

from .._deprecation import moved

__getattr__ = moved(__name__, {
    "Clocked": "pytest_flockai.control.clocked.Clocked",
    "Control": "pytest_flockai.control.clocked.Control",
    "DONE": "pytest_flockai.control.clocked.DONE",
    "Navigation": "pytest_flockai.control.clocked.Navigation",
    "STAGES": "pytest_flockai.control.clocked.STAGES",
    "SimulationError": "pytest_flockai.control.clocked.SimulationError",
})
