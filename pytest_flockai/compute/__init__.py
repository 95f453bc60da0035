"""On-board and ground computers: datasheet profiles, runtimes, the latency model
(``predict_latency``), per-node network costs (``analyze``), a team's own computer from its
datasheet (``computer``) and profiles measured on the computer (``profile``)."""

from .devices import DEVICES, Device, device, devices
from .graph import NetworkCost, NodeCost, analyze
from .own import computer, computers
from .predict import LatencyFallbackWarning, LatencyPrediction, predict_latency
from .profile import MeasuredDevice, profile
from .runtimes import PRECISIONS, RUNTIMES, TARGETS

__all__ = ["DEVICES", "PRECISIONS", "RUNTIMES", "TARGETS", "Device", "LatencyFallbackWarning",
           "LatencyPrediction", "device", "devices", "predict_latency"]
__all__ += ["MeasuredDevice", "NetworkCost", "NodeCost", "analyze", "computer", "computers",
            "profile"]
