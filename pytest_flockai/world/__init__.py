"""The world: ground, scenery, people and wind."""

from .wind import Wind
from .world import World

__all__ = ["Wind", "World"]
