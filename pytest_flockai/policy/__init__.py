"""Policies: what the drone decides during the flight from what it knows.

``Mission(policies=[...])`` takes ``Policy`` subclasses (your own ``decide(t, drone)``),
``Rule`` (when a condition holds, do actions), and the perception policies
``Follow``, ``SearchThenOrbit`` and ``MarkerLanding``. See ``policy.base`` for what a policy sees and
the actions it can take, and docs/how-to/policies.md.
"""

from .base import Cockpit, Delivered, Link, Policy, register_kpis
from .follow import ON_LOST, Follow, SearchThenOrbit
from .geofence import Geofence
from .landing import MarkerLanding
from .rules import (
                    Action,
                    DisableTask,
                    EnableTask,
                    GoTo,
                    Hold,
                    Land,
                    ResumePlan,
                    ReturnHome,
                    Rule,
                    SetExecution,
                    SetModel,
                    SetPeriod,
)
from .together import GroundStation, SharedSearch

__all__ = ["Action", "Cockpit", "Delivered", "DisableTask", "EnableTask", "Follow", "Geofence", "GoTo", "GroundStation", "Hold",
           "Land", "Link", "MarkerLanding", "ON_LOST", "Policy", "ResumePlan", "ReturnHome", "Rule",
           "SearchThenOrbit", "SetExecution", "SharedSearch", "SetModel", "SetPeriod", "register_kpis"]
