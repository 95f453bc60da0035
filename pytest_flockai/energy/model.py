"""Moved to ``pytest_flockai.energy.tree``; the old path warns once per name
(``_deprecation.py``) and will be removed."""

from .._deprecation import moved

__getattr__ = moved(__name__, {
    "EnergyModel": "pytest_flockai.energy.tree.EnergyModel",
    "Group": "pytest_flockai.energy.tree.Group",
    "Meter": "pytest_flockai.energy.tree.Meter",
})
