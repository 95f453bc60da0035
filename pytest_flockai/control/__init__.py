"""Flight control: the cascaded controller, trajectories and pilots."""

from .controller import CascadedController
from .pilots import Hover, Orbit, Pilot, Waypoints, ZigZag

__all__ = ["CascadedController", "Hover", "Orbit", "Pilot", "Waypoints", "ZigZag"]
