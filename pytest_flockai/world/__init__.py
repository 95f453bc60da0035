"""The world: ground, scenery, people (standing or walking: ``actors``), wind and the atmosphere."""

from . import actors
from .atmosphere import Atmosphere
from .truth import CameraModel, Truth, gimbal_pose, visible_people
from .wind import Wind
from .world import World

__all__ = ["actors", "Atmosphere", "CameraModel", "Truth", "Wind", "World", "gimbal_pose", "visible_people"]
