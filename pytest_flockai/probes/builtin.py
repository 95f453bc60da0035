"""The built-in probes: the paper's Table 1 metrics plus what CI gates need.

They read the simulated drone (not the host): the on-board computer's busy
time comes from the ML tasks, bytes from the radio link, energy from the
energy meter. Their metric names are the KPI names of ``kpis.py``.
"""

from __future__ import annotations

from .. import kpis as _kpis
from .base import Metric, Probe


def _metrics(*names: str, kind: str = "gauge") -> tuple[Metric, ...]:
    out = []
    for n in names:
        k = _kpis.REGISTRY[n]       # built-in names only: in the table
        out.append(Metric(n, k.unit, k.description, k.better, kind))
    return tuple(out)


class FlightProbe(Probe):
    """The flight book: time per phase, distance, top speed, tracking error, crash."""

    name = "flight"
    builtin = True
    metrics = (_metrics("flight_time_s", "takeoff_time_s", "hover_time_s", "move_time_s",
                        "accel_time_s", "landing_time_s", kind="timer")
               + _metrics("distance_m", kind="counter")
               + _metrics("max_speed_mps", "tracking_error_max_m", "crashed"))

    def collect(self, v) -> dict:
        pt = v.phase_time
        return {"flight_time_s": pt[0] + pt[1] + pt[2] + pt[3] + pt[4], "takeoff_time_s": pt[0],
                "hover_time_s": pt[1], "move_time_s": pt[2], "accel_time_s": pt[3],
                "landing_time_s": pt[4], "distance_m": v.distance_m, "max_speed_mps": v.max_speed_mps,
                "tracking_error_max_m": v.tracking_error_max_m, "crashed": 1.0 if v.crashed else 0.0}


class EnergyProbe(Probe):
    """The energy meter: energy per component and its shares, mean power, battery
    remaining and the endurance projected from the energy used so far."""

    name = "energy"
    builtin = True
    metrics = (_metrics("energy_total_j", "energy_motors_j", "energy_proc_j", "energy_comm_j",
                        "energy_battery_loss_j", kind="counter")
               + _metrics("energy_share_motors", "energy_share_proc", "energy_share_comm",
                          "battery_remaining", kind="ratio")
               + _metrics("mean_power_w", "endurance_s", "battery_v_min"))

    def collect(self, v) -> dict:
        tops = v.energy_by_top()
        e_tot = sum(tops.values())
        e_m, e_p, e_c = tops.get("motors", 0.0), tops.get("proc", 0.0), tops.get("comm", 0.0)
        t = v.t
        mean_p = e_tot / t if t > 0 else 0.0
        drain = e_tot + v.battery_loss_j          # the battery gives up the load and its own loss
        share = (lambda e: e / e_tot) if e_tot > 0 else (lambda e: 0.0)
        return {"energy_total_j": e_tot, "energy_motors_j": e_m, "energy_proc_j": e_p,
                "energy_comm_j": e_c, "energy_battery_loss_j": v.battery_loss_j,
                "battery_v_min": v.battery_v_min, "energy_share_motors": share(e_m),
                "energy_share_proc": share(e_p), "energy_share_comm": share(e_c), "mean_power_w": mean_p,
                "battery_remaining": max(0.0, 1.0 - drain / v.battery_usable_j),
                "endurance_s": v.battery_usable_j * t / drain if drain > 0 else float("inf")}


class ComputeProbe(Probe):
    """The simulated on-board computer: busy fraction and time (from ML tasks),
    storage I/O time, memory in use (OS baseline plus loaded models) over the
    device's memory."""

    name = "compute"
    builtin = True
    metrics = (_metrics("cpu_utilization", "mem_utilization", kind="ratio")
               + _metrics("cpu_time_s", "io_time_s", kind="timer"))

    def collect(self, v) -> dict:
        t = v.t
        return {"cpu_utilization": v.cpu_time_s / t if t > 0 else 0.0, "cpu_time_s": v.cpu_time_s,
                "io_time_s": v.io_time_s, "mem_utilization": v.mem_utilization}


class CommProbe(Probe):
    """The radio: kilobytes and packets sent and received."""

    name = "comm"
    builtin = True
    metrics = _metrics("kbytes_in", "kbytes_out", "packets_in", "packets_out", kind="counter")

    def collect(self, v) -> dict:
        return {"kbytes_in": v.bytes_in / 1000.0, "kbytes_out": v.bytes_out / 1000.0,
                "packets_in": float(v.packets_in), "packets_out": float(v.packets_out)}


ML_METRICS = (_metrics("inference_count", "frames_dropped", "inference_failures", kind="counter")
              + _metrics("inference_latency_p50_s", "inference_latency_p95_s",
                         "inference_latency_max_s", kind="timer")
              + _metrics("count_mae", "detection_delay_frames")
              + _metrics("detection_precision", "detection_recall", kind="ratio"))


def _finite(d: dict, names) -> dict:
    return {k: float(d[k]) for k in names if k in d and d[k] == d[k]}


class MLProbe(Probe):
    """The ML tasks together (latency over all inferences, summed counts); the
    KPIs of each task are also published under the task's name by a TaskProbe."""

    name = "ml"
    builtin = True
    metrics = ML_METRICS

    def collect(self, v) -> dict:
        return _finite(v.task_kpis, self._metric_names)


class TaskProbe(Probe):
    """One ML task's KPIs, as ``<task>.<kpi>`` (added by the mission per task)."""

    metrics = ML_METRICS + _metrics("cpu_time_s", kind="timer")

    def __init__(self, task_name: str, **kw) -> None:
        super().__init__(name=task_name, **kw)

    def collect(self, v) -> dict:
        return _finite(v.task_kpis_by_task.get(self.name, {}), self._metric_names)


BUILTIN = (FlightProbe, EnergyProbe, ComputeProbe, CommProbe, MLProbe)


def default_probes() -> list[Probe]:
    """A fresh instance of every built-in probe (1 s period)."""
    return [cls() for cls in BUILTIN]
