"""Sensors: navigation (GPS, IMU, compass, barometer, rangefinder, battery), custom
data (functions, random kernels, CSV replay), cameras (rendered, replayed) and
dataset export. See ``base.py`` for the interface the mission loop calls.

OpenGL is needed only when a rendered ``Camera`` produces its first frame."""

from ..world.truth import CameraModel, Truth, gimbal_pose, visible_people
from .base import FunctionSensor, Sensor, SensorSuite
from .camera import Camera
from .conditions import Conditions
from .custom import CsvSensor, TemperatureSensor
from .dataset import export_dataset
from .nav import GPS, IMU, Barometer, BatterySensor, Compass, Rangefinder
from .replay import ReplayCamera
from .views import ViewSet, render_views

__all__ = ["Conditions", "ViewSet", "GPS", "IMU", "Barometer", "BatterySensor", "Camera", "CameraModel", "Compass",
           "CsvSensor", "FunctionSensor", "Rangefinder", "ReplayCamera", "Sensor", "SensorSuite",
           "TemperatureSensor", "Truth", "export_dataset", "gimbal_pose", "render_views",
           "visible_people"]
