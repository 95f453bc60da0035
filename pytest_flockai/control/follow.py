"""Moved to ``pytest_flockai.control.tracking``; the old path warns once per name
(``_deprecation.py``) and will be removed."""

from .._deprecation import moved

__getattr__ = moved(__name__, {
    "Goto": "pytest_flockai.control.tracking.Goto",
    "Pilot": "pytest_flockai.control.tracking.Pilot",
    "Resume": "pytest_flockai.control.tracking.Resume",
    "Track": "pytest_flockai.control.tracking.Track",
    "Tracker": "pytest_flockai.control.tracking.Tracker",
    "Waypoints": "pytest_flockai.control.tracking.Waypoints",
    "focal_px": "pytest_flockai.control.tracking.focal_px",
    "gimbal_pose": "pytest_flockai.control.tracking.gimbal_pose",
    "ground_point": "pytest_flockai.control.tracking.ground_point",
    "plan_left": "pytest_flockai.control.tracking.plan_left",
    "yaw_of": "pytest_flockai.control.tracking.yaw_of",
})
