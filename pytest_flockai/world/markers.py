"""Moved to ``pytest_flockai.world.aruco``; the old path warns once per name
(``_deprecation.py``) and will be removed."""

from .._deprecation import moved

__getattr__ = moved(__name__, {
    "CELLS": "pytest_flockai.world.aruco.CELLS",
    "DICTIONARIES": "pytest_flockai.world.aruco.DICTIONARIES",
    "TEXEL_PER_CELL": "pytest_flockai.world.aruco.TEXEL_PER_CELL",
    "THICKNESS_M": "pytest_flockai.world.aruco.THICKNESS_M",
    "TOP_Z": "pytest_flockai.world.aruco.TOP_Z",
    "add_marker": "pytest_flockai.world.aruco.add_marker",
    "aruco_dictionary": "pytest_flockai.world.aruco.aruco_dictionary",
    "atomic_write": "pytest_flockai.world.aruco.atomic_write",
    "marker_file": "pytest_flockai.world.aruco.marker_file",
    "marker_image": "pytest_flockai.world.aruco.marker_image",
})
