"""Computer profiles: a datasheet per computer (compute units, bandwidth, power, runtimes).

A ``Device`` is what a task runs on. What the rest of the code reads stays as it was:
``name``, ``idle_w`` and ``active_w`` (W at the board's input: idle, and busy running
inference, measured where published, else the datasheet's), ``memory_mb``, ``source``, and
the MAC-count rule's ``macs_per_s`` and ``overhead_s`` (used only for a model known by its
MAC count alone). The latency model (``compute.predict``) reads the datasheet: ``units``
(each unit's peak multiply-accumulates per second per precision), ``bandwidth_gbs`` and
``deployments`` (the ``runtime/target`` pairs it can run, see ``compute.runtimes``).

The datasheets come from ``compute/data/computers.toml`` (sources next to every figure
there), read by ``compute.datasheets``; ``DEVICES`` maps the profile names to them.
"""

from __future__ import annotations

from ..errors import ConfigError, close_matches
from ._device import Device, Unit
from .datasheets import load_devices

DEVICES: dict[str, Device] = load_devices()


def devices() -> list[str]:
    """Names of the known device profiles."""
    return sorted(DEVICES)


def device(name: str) -> Device:
    """The profile named ``name`` (``devices()`` lists them); ConfigError otherwise."""
    try:
        return DEVICES[name]
    except (KeyError, TypeError):
        raise ConfigError(f"unknown device {name!r}{close_matches(str(name), DEVICES)}; "
                          f"available: {', '.join(devices())}") from None


__all__ = ["DEVICES", "Device", "Unit", "device", "devices"]
