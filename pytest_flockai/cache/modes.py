"""The cache's modes and the share of hits ``verify`` flies again: the settings the
light package module (``cache/__init__``, loaded in every pytest run) checks and the
store (``store.py``, loaded on first use) applies. They live below both, so that the
store never imports its own package module (which loads the store lazily)."""

from __future__ import annotations

MODES = ("off", "read", "write", "readwrite", "verify")
#: the share of hits ``verify`` flies again unless told
VERIFY_FRACTION = 0.1

__all__ = ["MODES", "VERIFY_FRACTION"]
