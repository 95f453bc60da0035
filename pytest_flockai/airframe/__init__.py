"""Airframes: blueprints, the Drone, and its MuJoCo model."""

from .drone import Drone, blueprints, drone
from .params import Airframe, Battery, Camera, Radio, Rotor, Sim

__all__ = ["Airframe", "Battery", "Camera", "Drone", "Radio", "Rotor", "Sim", "blueprints", "drone"]
