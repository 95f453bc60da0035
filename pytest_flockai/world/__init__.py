"""The world: ground, scenery, people and wind."""

from .truth import CameraModel, Truth, gimbal_pose, visible_people
from .wind import Wind
from .world import World

__all__ = ["CameraModel", "Truth", "Wind", "World", "gimbal_pose", "visible_people"]
