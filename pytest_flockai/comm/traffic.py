"""Radio traffic of one drone: what was sent and received, and the health-check
heartbeats to the ground station.

``Traffic`` collects bytes and packets as they happen (heartbeats, ML
results, offloaded frames); the energy integrator drains the pending counts
once per energy interval and charges them to the radio component, and the
totals feed the comm KPIs. ``Heartbeats`` is a clocked component: one
heartbeat of ``heartbeat_bytes`` up and a 64-byte acknowledgement down every
``heartbeat_period_s`` (the blueprint's ``[radio]``).
"""

from __future__ import annotations

from ..clock import CLOCK_EPS, Clocked

#: bytes of the ground station's acknowledgement of a heartbeat
ACK_BYTES = 64


class Traffic:
    __slots__ = ("tx_b", "tx_p", "rx_b", "rx_p", "bytes_out", "bytes_in", "packets_out",
                 "packets_in")

    def __init__(self):
        self.tx_b = self.tx_p = self.rx_b = self.rx_p = 0              # pending
        self.bytes_out = self.bytes_in = self.packets_out = self.packets_in = 0   # drained totals

    def add(self, tx_b, tx_p, rx_b, rx_p) -> None:
        self.tx_b += tx_b
        self.tx_p += tx_p
        self.rx_b += rx_b
        self.rx_p += rx_p

    def drain(self):
        """(tx bytes, tx packets, rx bytes, rx packets) pending; adds them to the totals."""
        out = (self.tx_b, self.tx_p, self.rx_b, self.rx_p)
        self.bytes_out += out[0]
        self.packets_out += out[1]
        self.bytes_in += out[2]
        self.packets_in += out[3]
        self.tx_b = self.tx_p = self.rx_b = self.rx_p = 0
        return out


class Heartbeats(Clocked):
    def __init__(self, traffic: Traffic, radio):
        self.traffic = traffic
        self.period_s = radio.heartbeat_period_s
        self.bytes = int(radio.heartbeat_bytes)
        self._t_next = 0.0
        self.next_due = -CLOCK_EPS

    def step(self, t: float) -> None:
        self.advance_clock()
        tr = self.traffic
        tr.tx_b += self.bytes
        tr.tx_p += 1
        tr.rx_b += ACK_BYTES
        tr.rx_p += 1
