"""The energy integrator: the only place a flight's energy is summed.

A clocked component on its own clock (``energy_hz``, 20 Hz by default). At the
end of each interval (t_e, t] it builds the ``Usage`` of the interval (rotor
thrust and air-relative velocity sampled now; SoC busy time, radio bytes and
packets accumulated over it), asks the meter for the power of every energy
component, and adds power x interval to the energy used; ``finish`` charges
the last, partial interval when the flight ends.
"""

from __future__ import annotations

from ..clock import CLOCK_EPS, Clocked
from ..physics import to_body
from .components import Usage


class EnergyIntegrator(Clocked):
    """``meter``: an ``energy.Meter``; ``traffic``: the drone's ``comm.Traffic``;
    ``tasks``: the task scheduler (SoC busy time and task traffic) or None. The
    energy used (``state.energy_j``) is the battery's drain: the load's energy
    plus the battery circuit's I^2 R loss; its terminal voltage and cut-off go
    to ``state.battery_v`` and ``state.battery_cutoff``."""

    def __init__(self, state, meter, data, traffic, tasks, *, energy_hz: float, n_rotors: int):
        self.st, self.meter, self.traffic, self.tasks = state, meter, traffic, tasks
        self._act = data.act
        self.period_s = 1.0 / energy_hz
        self._t_next = self.period_s          # the first interval (0, period] is charged at its end
        self.next_due = self._t_next - CLOCK_EPS
        self.t_e = 0.0
        self.u = Usage(n_rotors)
        self._battery = getattr(meter, "battery", None)   # the meter's battery circuit

    def step(self, t: float) -> None:
        s, u = self.st, self.u
        edt = t - self.t_e
        u.dt = edt
        u.t = t
        u.airborne = s.airborne
        u.thrust = self._act.tolist()
        q, v, w = s.q, s.v, s.w
        u.v_rel_body = to_body(q, v[0] - w[0], v[1] - w[1], v[2] - w[2])
        if self.tasks is not None:
            busy = self._take_tasks(t)
            u.soc_busy = min(1.0, busy / edt) if edt > 0 else 0.0
        u.tx_bytes, u.tx_packets, u.rx_bytes, u.rx_packets = self.traffic.drain()
        power = self.meter.step(u)
        s.power = power
        s.energy_j += (power + getattr(self.meter, "last_loss", 0.0)) * edt   # drain: load + I^2 R
        s.battery_remaining = max(0.0, 1.0 - s.energy_j / s.e_usable)
        c = self._battery
        if c is not None:
            s.battery_v = c.voltage_v
            s.battery_cutoff = c.cutoff
        self.t_e = t
        self.advance_clock()

    def finish(self, t: float) -> None:
        """Charge the last partial interval (t_e, t]."""
        s, u = self.st, self.u
        t_e = self.t_e
        if self.tasks is not None:
            busy = self._take_tasks(t)
            u.soc_busy = min(1.0, busy / (t - t_e)) if t > t_e else 0.0
        if t > t_e:
            u.dt, u.t, u.airborne = t - t_e, t, s.airborne
            u.thrust = self._act.tolist()
            u.tx_bytes, u.tx_packets, u.rx_bytes, u.rx_packets = self.traffic.drain()
            p = self.meter.step(u)
            s.energy_j += (p + getattr(self.meter, "last_loss", 0.0)) * (t - t_e)
            self.t_e = t

    def _take_tasks(self, t) -> float:
        busy, tb, tp, rb, rp = self.tasks.take_usage(t)
        self.traffic.add(tb, tp, rb, rp)
        return busy
