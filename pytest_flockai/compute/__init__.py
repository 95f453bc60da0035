"""On-board and ground computers: datasheet profiles, runtimes and the latency model."""

from .devices import DEVICES, Device, device, devices
from .predict import LatencyFallbackWarning, LatencyPrediction, predict_latency
from .runtimes import PRECISIONS, RUNTIMES, TARGETS

__all__ = ["DEVICES", "PRECISIONS", "RUNTIMES", "TARGETS", "Device", "LatencyFallbackWarning",
           "LatencyPrediction", "device", "devices", "predict_latency"]
