"""Energy components: each turns one tick's usage into electrical power.

The interface is small on purpose so users can write their own::

    class Heater(Component):
        def __init__(self, watts):
            super().__init__("heater", "de-icing heater")
            self.watts = watts
        def power(self, u):            # u: Usage of this tick
            return self.watts if u.airborne else 0.0

A component may split its power into named ``parts`` (the motors of ``rotors.py`` report
induced, profile and climb/drag power): it then implements ``power_parts(u)``
returning one number per part. ``bind(drone)`` is called once before each
flight to precompute from the airframe; keep ``power`` cheap, it runs on the
simulated clock.
"""

from __future__ import annotations

from .. import _check
from ..errors import ConfigError


class Usage:
    """What the drone did during one energy tick; filled by the mission loop."""

    __slots__ = ("t", "dt", "airborne", "thrust", "v_rel_body", "soc_busy",
                 "tx_bytes", "tx_packets", "rx_bytes", "rx_packets", "io_busy")

    def __init__(self, rotor_count: int = 4):
        self.t = 0.0
        self.dt = 0.0
        self.airborne = False
        self.thrust = [0.0] * rotor_count      # N per rotor
        self.v_rel_body = (0.0, 0.0, 0.0)      # vehicle velocity relative to air, body frame
        self.soc_busy = 0.0                    # fraction of the tick the SoC was busy
        self.io_busy = 0.0
        self.tx_bytes = self.tx_packets = self.rx_bytes = self.rx_packets = 0


class Component:
    """Base class: a named source of power draw."""

    parts: tuple[str, ...] = ()

    def __init__(self, name: str, description: str = ""):
        if not isinstance(name, str) or not name or "." in name:
            raise ConfigError(f"component name = {name!r} is not allowed; expected a non-empty "
                              f"string without '.'")
        self.name = name
        self.description = description

    def bind(self, drone) -> None:
        """Precompute from the drone before a flight (optional)."""

    def bind_air_density(self, rho: float) -> None:
        """The flight's air density (kg/m^3), set before ``bind`` (optional)."""

    def power(self, u: Usage) -> float:  # pragma: no cover - interface
        raise NotImplementedError(f"{type(self).__name__}.power(usage) must return watts")

    def power_parts(self, u: Usage):
        return (self.power(u),)

    def set_description(self, text: str) -> Component:
        self.description = str(text)
        return self

    def describe(self) -> dict:
        out: dict = {"name": self.name, "type": type(self).__name__,
                     "description": self.description}
        out.update(self.params())
        if self.parts:
            out["parts"] = list(self.parts)
        return out

    def params(self) -> dict:
        return {}

    def __repr__(self):
        p = ", ".join(f"{k}={v!r}" for k, v in self.params().items())
        return f"{type(self).__name__}({self.name!r}{', ' if p else ''}{p})"


class Constant(Component):
    """A constant draw for the whole mission (flight controller, a sensor, I/O)."""

    def __init__(self, name: str, power_w: float, description: str = ""):
        super().__init__(name, description)
        self.power_w = power_w

    @property
    def power_w(self) -> float:
        return self._w

    @power_w.setter
    def power_w(self, value):
        self._w = _check.non_negative("power_w", value, where=f"component {self.name!r}")

    def set_power(self, watts: float) -> Constant:
        self.power_w = watts
        return self

    def power(self, u):
        return self._w

    def params(self):
        return {"power_w": self._w}


class SoC(Component):
    """On-board computer: idle power, active power while busy (ML tasks)."""

    parts = ("idle", "active")

    def __init__(self, name: str, idle_w: float, active_w: float, description: str = ""):
        super().__init__(name, description)
        where = f"component {name!r}"
        self.idle_w = _check.non_negative("idle_w", idle_w, where=where)
        self.active_w = _check.non_negative("active_w", active_w, where=where)

    @classmethod
    def of(cls, device, note: str = "") -> SoC:
        """The SoC of a compute ``Device`` (its idle and busy watts), named ``soc``."""
        return cls("soc", device.idle_w, device.active_w,
                   f"on-board computer {device.name}{note}")

    def power_parts(self, u):
        b = u.soc_busy
        return (self.idle_w * (1.0 - b), self.active_w * b)

    def power(self, u):
        b = u.soc_busy
        return self.idle_w * (1.0 - b) + self.active_w * b

    def params(self):
        return {"idle_w": self.idle_w, "active_w": self.active_w}


class RadioLinear(Component):
    """802.11-style linear model (Feeney and Nilsson 2001): per packet
    E = m * bytes + b for sending and receiving, plus an idle draw."""

    parts = ("idle", "tx", "rx")

    def __init__(self, name: str, *, tx_uj_per_byte, tx_uj_per_packet, rx_uj_per_byte,
                 rx_uj_per_packet, idle_w, description: str = ""):
        super().__init__(name, description)
        w = f"component {name!r}"
        self.tx_uj_per_byte = _check.non_negative("tx_uj_per_byte", tx_uj_per_byte, where=w)
        self.tx_uj_per_packet = _check.non_negative("tx_uj_per_packet", tx_uj_per_packet, where=w)
        self.rx_uj_per_byte = _check.non_negative("rx_uj_per_byte", rx_uj_per_byte, where=w)
        self.rx_uj_per_packet = _check.non_negative("rx_uj_per_packet", rx_uj_per_packet, where=w)
        self.idle_w = _check.non_negative("idle_w", idle_w, where=w)

    def power_parts(self, u):
        dt = u.dt
        if dt <= 0.0:
            return (self.idle_w, 0.0, 0.0)
        tx = (self.tx_uj_per_byte * u.tx_bytes + self.tx_uj_per_packet * u.tx_packets) * 1e-6 / dt
        rx = (self.rx_uj_per_byte * u.rx_bytes + self.rx_uj_per_packet * u.rx_packets) * 1e-6 / dt
        return (self.idle_w, tx, rx)

    def power(self, u):
        return sum(self.power_parts(u))

    def params(self):
        return {k: getattr(self, k) for k in ("tx_uj_per_byte", "tx_uj_per_packet",
                                               "rx_uj_per_byte", "rx_uj_per_packet", "idle_w")}


class RadioStates(Component):
    """Radio as power states (paper Eq. for E_comm): P_tx t_tx + P_rx t_rx + P_idle t_idle,
    times from bytes over the bit rate. The paper's Wi-Fi: 8.4 W tx/rx, 4.2 W idle."""

    parts = ("idle", "tx", "rx")

    def __init__(self, name: str, *, tx_w=8.4, rx_w=8.4, idle_w=4.2, bitrate_bps=6e6,
                 description: str = ""):
        super().__init__(name, description)
        w = f"component {name!r}"
        self.tx_w = _check.non_negative("tx_w", tx_w, where=w)
        self.rx_w = _check.non_negative("rx_w", rx_w, where=w)
        self.idle_w = _check.non_negative("idle_w", idle_w, where=w)
        self.bitrate_bps = _check.positive("bitrate_bps", bitrate_bps, where=w)

    def power_parts(self, u):
        dt = u.dt
        if dt <= 0.0:
            return (self.idle_w, 0.0, 0.0)
        # every byte's airtime is charged in full (a short tick must not lose it);
        # only the idle time is what is left of the tick
        t_tx = u.tx_bytes * 8.0 / self.bitrate_bps
        t_rx = u.rx_bytes * 8.0 / self.bitrate_bps
        idle = max(0.0, dt - t_tx - t_rx)
        return (self.idle_w * idle / dt, self.tx_w * t_tx / dt, self.rx_w * t_rx / dt)

    def power(self, u):
        return sum(self.power_parts(u))

    def params(self):
        return {"tx_w": self.tx_w, "rx_w": self.rx_w, "idle_w": self.idle_w,
                "bitrate_bps": self.bitrate_bps}
