"""A measured profile (``compute.profile``, written by ``flockai profile-device``) as a ``Device``.

Flights need more of a computer than its inference latencies: its idle and busy power (the
energy model's SoC), its memory, and a MAC rate for the work that is not an inference
(JPEG encoding, in-flight updates). ``as_device(measured)`` takes them from the datasheet
profile the measurement names (``MeasuredDevice.name``, or ``host["computer"]``, when it is
one of ``devices()``), else from ``raspberry-pi-4`` (FlockAI's computer), with the measured
busy and idle power in their place when the profile has them. The inference latencies
themselves come from the measured samples (``Device.measured``).
"""

from __future__ import annotations

from dataclasses import replace

from .devices import DEVICES, Device

FALLBACK = "raspberry-pi-4"


def is_measured(obj) -> bool:
    """A ``MeasuredDevice`` (it has measured latency samples to draw from)."""
    return hasattr(obj, "sample_latency") and hasattr(obj, "latency_samples")


def as_device(measured) -> Device:
    """The ``Device`` flights use for a measured profile (see the module docstring)."""
    host = getattr(measured, "host", None) or {}
    name = str(getattr(measured, "name", "") or "measured")
    base = DEVICES.get(name) or DEVICES.get(str(host.get("computer", ""))) or DEVICES[FALLBACK]
    idle = getattr(measured, "idle_w", None)
    busy = getattr(measured, "busy_w", None)
    return replace(base, name=name, idle_w=float(idle) if idle is not None else base.idle_w,
                   active_w=float(busy) if busy is not None else base.active_w,
                   source=f"measured profile {getattr(measured, 'path', '')!r} "
                          f"(power and memory: {base.name} unless measured)",
                   measured=measured)


__all__ = ["FALLBACK", "as_device", "is_measured"]
