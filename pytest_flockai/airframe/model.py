"""Moved to ``pytest_flockai.airframe.mjspec``; the old path warns once per name
(``_deprecation.py``) and will be removed."""

from .._deprecation import moved

__getattr__ = moved(__name__, {
    "AERO_SCALE": "pytest_flockai.airframe.mjspec.AERO_SCALE",
    "add_drone": "pytest_flockai.airframe.mjspec.add_drone",
    "build_model": "pytest_flockai.airframe.mjspec.build_model",
    "build_spec": "pytest_flockai.airframe.mjspec.build_spec",
    "drag_ellipsoid": "pytest_flockai.airframe.mjspec.drag_ellipsoid",
    "world_spec": "pytest_flockai.airframe.mjspec.world_spec",
})
