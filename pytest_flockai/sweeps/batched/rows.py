"""The KPIs of each batched variant from its final state (numpy), with the
built-in probes' formulas (``probes/builtin.py``): flight, energy, comm and
compute KPIs. No ML KPIs: the batched path flies no tasks."""

from __future__ import annotations

import math

import numpy as np

from ...comm.traffic import ACK_BYTES
from ...probes.builtin import BUILTIN
from .params import END_REASONS


def rows(s, nums, tops, book_dt) -> list[dict]:
    """One row per variant: end_reason, error, sim_time_s and the KPIs."""
    out = []
    for b, num in enumerate(nums):
        t = float(s["d"].time[b])
        end = END_REASONS[int(s["end"][b])]
        row = {"end_reason": end or "time_cap", "error": None, "sim_time_s": t}
        if end == "diverged":
            row["error"] = (f"SimulationError: simulation diverged at t = {t:.3f} s (position "
                            f"or velocity not finite) in the batched (MJX) flight")
        row.update(_flight(s, b, book_dt))
        row.update(_energy(s, b, num, tops, t))
        n_hb = float(s["hb_drained"][b])
        row.update({"kbytes_in": n_hb * ACK_BYTES / 1000.0,
                    "kbytes_out": n_hb * num.mission.hb_bytes / 1000.0,
                    "packets_in": n_hb, "packets_out": n_hb,
                    "cpu_utilization": 0.0, "cpu_time_s": 0.0, "io_time_s": 0.0,
                    "mem_utilization": float(num.mission.mem_utilization)})
        out.append({k: row[k] for k in _ORDER if k in row})
    return out


#: the core's column order: the built-in probes' metrics, in order
_ORDER = ["end_reason", "error", "sim_time_s"] + [m.name for cls in BUILTIN for m in cls.metrics]


def _flight(s, b, dt) -> dict:
    pt = [int(n) * dt for n in s["ticks"][b]]
    return {"flight_time_s": pt[0] + pt[1] + pt[2] + pt[3] + pt[4], "takeoff_time_s": pt[0],
            "hover_time_s": pt[1], "move_time_s": pt[2], "accel_time_s": pt[3],
            "landing_time_s": pt[4], "distance_m": float(s["dist"][b]),
            "max_speed_mps": float(s["vmax"][b]), "tracking_error_max_m": float(s["terr"][b]),
            "crashed": 1.0 if END_REASONS[int(s["end"][b])] == "crashed" else 0.0}


def _energy(s, b, num, tops, t) -> dict:
    leaf = np.asarray(s["e_leaf"][b], dtype=float)
    by_top: dict[str, float] = {}
    for name, e in zip(tops, leaf):
        by_top[name] = by_top.get(name, 0.0) + float(e)
    e_tot = sum(by_top.values())
    e_m, e_p, e_c = by_top.get("motors", 0.0), by_top.get("proc", 0.0), by_top.get("comm", 0.0)
    loss = float(s["loss_j"][b])
    drain = e_tot + loss
    usable = float(num.mission.e_usable)
    share = (lambda e: e / e_tot) if e_tot > 0 else (lambda e: 0.0)
    return {"energy_total_j": e_tot, "energy_motors_j": e_m, "energy_proc_j": e_p,
            "energy_comm_j": e_c, "energy_battery_loss_j": loss,
            "battery_v_min": float(s["b_vmin"][b]), "energy_share_motors": share(e_m),
            "energy_share_proc": share(e_p), "energy_share_comm": share(e_c),
            "mean_power_w": e_tot / t if t > 0 else 0.0,
            "battery_remaining": max(0.0, 1.0 - drain / usable),
            "endurance_s": usable * t / drain if drain > 0 else math.inf}
