"""Moved to ``pytest_flockai.sweeps.sweep_result``; the old path warns once per name
(``_deprecation.py``) and will be removed."""

from .._deprecation import moved

__getattr__ = moved(__name__, {
    "SweepResult": "pytest_flockai.sweeps.sweep_result.SweepResult",
})
