"""Per-task energy: what each ML task cost the drone's battery, and what is left.

``<task>.energy_j`` = ``<task>.compute_energy_j`` + ``<task>.radio_energy_j``:

- compute: the SoC busy seconds the task caused on the drone (its inferences on
  board, JPEG encoding of the frames it sends, in-flight updates), as charged to
  the energy model (``proc.soc``), times the SoC's active minus idle power: the
  energy the computer drew because the task ran (its idle draw is paid anyway). An
  inference on the CPU is charged at its share of the cores (its threads over the
  cores: TF Lite's one thread on a four-core Pi, a quarter).
  A remote task's inference runs on the ground station: only its encoding stays;
- radio: the bytes and packets the task sent and received, as charged, at the
  radio's per-byte and per-packet energies (``comm.radio``, the linear model of
  Feeney and Nilsson 2001; for the power-state model, the airtime at the tx/rx
  power above idle).

``energy_untasked_j``: the ``proc`` and ``comm`` groups' energy minus the tasks'
(flight controller, idle computer and radio, sensors, I/O, telemetry traffic), so
the per-task figures plus the remainder sum to the groups' totals.
"""

from __future__ import annotations

from ..energy.components import RadioLinear, RadioStates, SoC


def _leaf(model, path: str):
    for p, comp in model.leaves():
        if p == path:
            return comp
    return None


def radio_joules(radio, tx_b, tx_p, rx_b, rx_p) -> float:
    """Energy (J) of the traffic above the radio's idle draw."""
    if isinstance(radio, RadioLinear):
        return 1e-6 * (radio.tx_uj_per_byte * tx_b + radio.tx_uj_per_packet * tx_p
                       + radio.rx_uj_per_byte * rx_b + radio.rx_uj_per_packet * rx_p)
    if isinstance(radio, RadioStates):
        return (8.0 / radio.bitrate_bps) * ((radio.tx_w - radio.idle_w) * tx_b
                                            + (radio.rx_w - radio.idle_w) * rx_b)
    return 0.0


def task_energy_kpis(names, charged, meter) -> dict:
    """``names``: the tasks; ``charged``: per task [busy s, tx bytes, tx packets, rx bytes,
    rx packets] as charged to ``meter`` (an ``energy.Meter``)."""
    soc = _leaf(meter.model, "proc.soc")
    radio = _leaf(meter.model, "comm.radio")
    extra = (soc.active_w - soc.idle_w) if isinstance(soc, SoC) else 0.0
    out, total = {}, 0.0
    for name, (busy, tb, tp, rb, rp) in zip(names, charged):
        cj, rj = busy * extra, radio_joules(radio, tb, tp, rb, rp)
        out[f"{name}.compute_energy_j"] = cj
        out[f"{name}.radio_energy_j"] = rj
        out[f"{name}.energy_j"] = cj + rj
        total += cj + rj
    groups = meter.totals_by_top()
    out["energy_untasked_j"] = groups.get("proc", 0.0) + groups.get("comm", 0.0) - total
    return out
