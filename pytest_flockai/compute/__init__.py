"""On-board and ground computers: device profiles (power, throughput), per-node
network costs (``analyze``) and profiles measured on the computer (``profile``)."""

from .devices import DEVICES, Device, device, devices
from .graph import NetworkCost, NodeCost, analyze
from .profile import MeasuredDevice, profile

__all__ = ["DEVICES", "Device", "device", "devices"]
__all__ += ["MeasuredDevice", "NetworkCost", "NodeCost", "analyze", "profile"]
