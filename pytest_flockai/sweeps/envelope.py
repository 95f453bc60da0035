"""Moved to ``pytest_flockai.sweeps.envelope_files``; the old path warns once per name
(``_deprecation.py``) and will be removed."""

from .._deprecation import moved

__getattr__ = moved(__name__, {
    "ConfigError": "pytest_flockai.sweeps.envelope_files.ConfigError",
    "atomic_write": "pytest_flockai.sweeps.envelope_files.atomic_write",
    "available": "pytest_flockai.sweeps.envelope_files.available",
    "display_unit": "pytest_flockai.sweeps.envelope_files.display_unit",
    "figure": "pytest_flockai.sweeps.envelope_files.figure",
    "label": "pytest_flockai.sweeps.envelope_files.label",
    "save": "pytest_flockai.sweeps.envelope_files.save",
    "summary": "pytest_flockai.sweeps.envelope_files.summary",
})
