"""Moved to ``pytest_flockai.policy.inputs``; the old path warns once per name
(``_deprecation.py``) and will be removed."""

from .._deprecation import moved

__getattr__ = moved(__name__, {
    "Delivered": "pytest_flockai.policy.inputs.Delivered",
    "Link": "pytest_flockai.policy.inputs.Link",
})
