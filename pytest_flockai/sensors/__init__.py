"""Sensors: navigation (GPS, IMU, compass, barometer, rangefinder, battery), custom
data (functions, random kernels, CSV replay), cameras (rendered, replayed) and
dataset export. See ``base.py`` for the interface the mission loop calls.

OpenGL is needed only when a rendered ``Camera`` produces its first frame."""

from .._deprecation import moved as _moved
from .base import FunctionSensor, Sensor, SensorSuite
from .camera import Camera
from .conditions import Conditions
from .custom import CsvSensor, TemperatureSensor
from .dataset import export_dataset
from .nav import GPS, IMU, Barometer, BatterySensor, Compass, Rangefinder
from .replay import ReplayCamera
from .views import ViewSet, render_views

__all__ = ["Conditions", "ViewSet", "GPS", "IMU", "Barometer", "BatterySensor", "Camera", "Compass",
           "CsvSensor", "FunctionSensor", "Rangefinder", "ReplayCamera", "Sensor", "SensorSuite",
           "TemperatureSensor", "export_dataset", "render_views"]

#: the world's truth (what the camera could see) has one home, ``fa.world``
__getattr__ = _moved(__name__, {n: f"pytest_flockai.world.{n}"
                               for n in ("CameraModel", "Truth", "gimbal_pose", "visible_people")})
