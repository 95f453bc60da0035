"""The world: ground, scenery, people, wind and the atmosphere."""

from .atmosphere import Atmosphere
from .truth import CameraModel, Truth, gimbal_pose, visible_people
from .wind import Wind
from .world import World

__all__ = ["Atmosphere", "CameraModel", "Truth", "Wind", "World", "gimbal_pose", "visible_people"]
