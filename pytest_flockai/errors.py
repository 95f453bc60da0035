"""One error hierarchy for the whole package.

``ConfigError`` is also a ``ValueError`` so callers that already catch bad
input the standard way keep working. Every message names the field, the bad
value and what is allowed, and is raised where the value enters.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable
from typing import Any

__all__ = ["ConfigError", "FlockAIError", "SimulationError", "WriteError"]


class FlockAIError(Exception):
    """Base class of every error pytest-flockai raises on purpose."""


class ConfigError(FlockAIError, ValueError):
    """Bad input: a field, its value and what is allowed."""


class SimulationError(FlockAIError, RuntimeError):
    """The simulation itself failed (diverged, produced NaN, ...)."""

    # Set by the flight loop before the error leaves Mission.run / Fleet.run (annotations
    # only: ``getattr(exc, "end_reason", "diverged")`` relies on them being absent before).
    #: the partial result: a FlightResult, or a FleetResult for a fleet
    result: Any
    #: why the flight ended ("wall_time", ...), when it is not a divergence
    end_reason: str


class WriteError(FlockAIError, OSError):
    """A file could not be written (a full disk, a read-only or missing folder, a
    folder or a device where the file should be): the message names the file. Also
    an ``OSError``, so callers that catch I/O errors keep working."""


def close_matches(word: str, choices: Iterable[str], n: int = 3) -> str:
    """' (did you mean: a, b?)' or '' when nothing is close."""
    hits = difflib.get_close_matches(str(word), list(choices), n=n, cutoff=0.5)
    return f" (did you mean: {', '.join(hits)}?)" if hits else ""
