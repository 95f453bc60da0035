"""On-board and ground computers: device profiles (power, throughput)."""

from .devices import DEVICES, Device, device, devices

__all__ = ["DEVICES", "Device", "device", "devices"]
