"""The names of a flight's stages and phases, defined once.

Stages are what the drone is commanded to do (the stage machine,
``control.stages``); phases are what it is doing (the flight book, the
paper's Table 1 time metrics). Telemetry stores both as categories.
"""

from __future__ import annotations

from enum import IntEnum


class Stage(IntEnum):
    """What the drone is commanded to do (the stage machine)."""

    TAKEOFF = 0
    PILOT = 1
    RETURN = 2
    LANDING = 3
    DONE = 4


class Phase(IntEnum):
    """What the drone is doing (the flight book; the paper's Table 1 time metrics)."""

    TAKEOFF = 0
    HOVER = 1
    MOVE = 2
    ACCELERATING = 3
    LANDING = 4
    LANDED = 5


STAGES = ("takeoff", "pilot", "return", "landing", "done")
PHASES = tuple(p.name.lower() for p in Phase)
