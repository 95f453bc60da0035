"""The registry of KPI names: unit (SI), description, which direction is better.

``better`` is "higher", "lower" or None (no better direction: not gated by
baselines). Custom probe metrics are named ``<probe>.<metric>`` and registered
at run time with ``register``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .errors import ConfigError

__all__ = ["ABS_TOL", "BUILTIN", "FAMILIES", "KPI", "REGISTRY", "UNIT_ABS_TOL", "abs_tolerance", "get",
           "names", "register"]


@dataclass(frozen=True)
class KPI:
    """One KPI: its name, SI unit, which way is better and what it measures."""

    name: str
    unit: str          # "s", "J", "W", "m", "m/s", "kB", "V", "fraction" (0..1), "count", "1" (custom, unitless)
    better: str | None
    description: str
    abs_tol: float | None = None   # a change this small is noise (SI); None: the unit's default


_ROWS = [
    # flight
    ("flight_time_s", "s", "higher", "time from take-off to landing (or to the end of the flight)"),
    ("takeoff_time_s", "s", None, "time spent climbing to the mission altitude"),
    ("hover_time_s", "s", None, "airborne time below 0.5 m/s"),
    ("move_time_s", "s", None, "airborne time moving at steady speed"),
    ("accel_time_s", "s", None, "airborne time accelerating or braking (> 0.5 m/s^2)"),
    ("landing_time_s", "s", None, "time spent descending to land"),
    ("distance_m", "m", None, "path length flown"),
    ("max_speed_mps", "m/s", None, "highest ground speed"),
    ("tracking_error_max_m", "m", "lower", "largest distance between the drone and the pilot's reference"),
    ("crashed", "count", "lower", "1 if the flight ended in a crash, else 0"),
    # energy
    ("energy_total_j", "J", "lower", "E_total = E_motors + E_proc + E_comm"),
    ("energy_motors_j", "J", "lower", "energy drawn by the motors"),
    ("energy_proc_j", "J", "lower", "energy drawn by processing (flight controller, SoC, I/O, sensors)"),
    ("energy_comm_j", "J", "lower", "energy drawn by the radio"),
    ("energy_battery_loss_j", "J", "lower", "I^2 R loss inside the battery (drains it on top of E_total)"),
    ("battery_v_min", "V", "higher", "lowest battery terminal voltage under load"),
    ("energy_share_motors", "fraction", None, "E_motors / E_total"),
    ("energy_share_proc", "fraction", "lower", "E_proc / E_total"),
    ("energy_share_comm", "fraction", "lower", "E_comm / E_total"),
    ("mean_power_w", "W", "lower", "mean electrical power over the flight"),
    ("battery_remaining", "fraction", "higher", "usable battery energy left at the end, fraction"),
    ("endurance_s", "s", "higher", "projected flight time to depletion at the mission's mean drain (load plus battery loss)"),
    # compute
    ("cpu_utilization", "fraction", "lower", "busy fraction of the on-board computer"),
    ("cpu_time_s", "s", "lower", "busy time of the on-board computer"),
    ("io_time_s", "s", "lower", "time spent on storage I/O"),
    ("mem_utilization", "fraction", "lower", "memory in use on the on-board computer, fraction"),
    # comm
    ("kbytes_in", "kB", None, "kilobytes received by the drone"),
    ("kbytes_out", "kB", None, "kilobytes sent by the drone"),
    ("packets_in", "count", None, "packets received by the drone"),
    ("packets_out", "count", None, "packets sent by the drone"),
    # ML
    ("inference_count", "count", None, "inferences completed"),
    ("inference_latency_p50_s", "s", "lower", "median inference latency, capture to result"),
    ("inference_latency_p95_s", "s", "lower", "95th percentile inference latency"),
    ("inference_latency_max_s", "s", "lower", "largest inference latency"),
    ("frames_dropped", "count", "lower", "frames skipped because the model was busy"),
    ("inference_failures", "count", "lower", "inferences whose model raised (the flight went on)"),
    ("count_mae", "count", "lower", "mean absolute error of the people count"),
    ("detection_precision", "fraction", "higher", "precision of crowd detection"),
    ("detection_recall", "fraction", "higher", "recall of crowd detection"),
    ("detection_delay_frames", "count", "lower", "frames from a crowd (detection tasks: an object) "
     "entering view until detected"),
    # ML: object detection (COCO, pycocotools) and classification
    ("map50", "fraction", "higher", "mean average precision over the classes at IoU 0.5 (COCO)"),
    ("map50_95", "fraction", "higher", "mean average precision over IoU 0.50:0.95 (COCO)"),
    ("precision", "fraction", "higher", "detections at the score threshold that match an object"),
    ("recall", "fraction", "higher", "objects matched by a detection at the score threshold"),
    ("objects_missed", "fraction", "lower", "objects in view never detected"),
    ("accuracy", "fraction", "higher", "frames whose predicted classes are exactly right"),
    # closed loop (fa.policy.Follow, SearchThenOrbit, MarkerLanding): scored against the truth
    # after the flight, never used in a decision
    ("time_to_detect_s", "s", "lower", "start of the plan to the first confirmed target"),
    ("track_error_p95_m", "m", "lower", "95th percentile horizontal distance drone to followed "
     "target while following"),
    ("track_error_mean_m", "m", "lower", "mean horizontal distance drone to followed target "
     "while following"),
    ("track_lost_count", "count", "lower", "times the followed target's track was lost"),
    ("track_lost_s", "s", "lower", "time spent with the target's track lost"),
    ("track_rejected_stale", "count", "lower", "results older than the policy's max_age_s "
     "(Follow: lost_after_s) at delivery, refused by a perception policy"),
    ("track_rejected_implausible", "count", "lower", "tracks dropped for moving faster than "
     "their class can (a false positive)"),
    ("landing_error_m", "m", "lower", "horizontal distance from the touchdown point to the "
     "landing marker's centre"),
    ("targets_found", "count", "higher", "distinct targets a search confirmed"),
    ("time_to_find_all_s", "s", "lower", "start of the plan until every target was found "
     "(NaN unless all were)"),
    ("images_scored", "count", None, "frames (images) a detection or classification task scored"),
    # ML: per-task energy (ml/task_energy.py); each as '<task>.<kpi>'
    ("energy_j", "J", "lower", "energy the task cost the battery: compute_energy_j + radio_energy_j"),
    ("compute_energy_j", "J", "lower", "on-board computer's busy time the task caused, at its "
     "active-over-idle power"),
    ("radio_energy_j", "J", "lower", "the radio's energy for the bytes and packets the task sent and "
     "received"),
    ("energy_untasked_j", "J", None, "proc and comm energy not caused by a task (flight controller, "
     "idle computer and radio, sensors, telemetry)"),
    # fleet (fa.Fleet); each drone's own KPIs are '<drone name>.<kpi>'
    ("fleet.drones", "count", None, "drones in the fleet"),
    ("fleet.makespan_s", "s", "lower", "time until the last drone's flight ended"),
    ("fleet.coverage_time_s", "s", "lower", "first drone starting its plan to the last ending it"),
    ("fleet.coverage_fraction", "fraction", "higher", "share of the fleet's area flown over "
     "within swath_m / 2 during the pilots' plans"),
    ("fleet.min_separation_m", "m", "higher", "smallest distance between two airborne drones"),
    ("fleet.crashes", "count", "lower", "drones whose flight ended in a crash"),
    ("fleet.energy_total_j", "J", "lower", "sum of the drones' energy_total_j"),
    ("fleet.targets_found", "count", "higher", "a search together (fa.policy.SharedSearch): "
     "distinct people confirmed"),
    ("fleet.time_to_find_all_s", "s", "lower", "a search together: first plan start until "
     "every person was confirmed (NaN unless all were)"),
    ("fleet.reports", "count", None, "a search together: detections reported to the ground station"),
    ("fleet.assignments", "count", None, "a search together: drones sent to confirm a report"),
    ("fleet.associations", "count", None, "a search together: reports taken as a known target "
     "(inside its gate), not assigned again"),
    ("fleet.handoffs", "count", None, "a search together: diverted drones whose unflown legs "
     "were shared with the free drones (GroundStation share)"),
    ("offload.latency_p95_s", "s", "lower", "fleet offload: 95th percentile capture-to-result latency"),
    ("link.queue_delay_p95_s", "s", "lower", "fleet offload: 95th percentile wait for the channel"),
    ("ground.queue_delay_mean_s", "s", "lower", "fleet offload: mean wait for the ground device"),
    ("ground.queue_delay_p95_s", "s", "lower", "fleet offload: 95th percentile wait for the ground device"),
    ("ground.utilization", "fraction", None, "fleet offload: ground device busy time / makespan"),
]

#: ``<family>.<qualifier>`` KPIs (per class, altitude band, box size): a fraction, higher better
FAMILIES = {"map50": "per class", "precision": "per class", "recall": "per class, altitude "
            "band (alt_<lo>_<hi>m) or box height (size_<band>px)"}

REGISTRY: dict[str, KPI] = {r[0]: KPI(*r) for r in _ROWS}
#: the built-in names (REGISTRY also holds the KPIs registered at run time)
BUILTIN = frozenset(REGISTRY)

#: Absolute tolerance by unit: a change of a KPI smaller than this is noise, never a
#: regression, whatever the relative threshold (a 0.002 % CPU change is not news).
#: Chosen below what any budget in the examples resolves: 1 ms, 10 mJ, 1 mW, 1 mm,
#: 1 mV, 1 byte, 0.01 percentage point; counts are exact.
UNIT_ABS_TOL = {"s": 1e-3, "J": 1e-2, "W": 1e-3, "m": 1e-3, "m/s": 1e-3, "kB": 1e-3,
                "V": 1e-3, "fraction": 1e-4, "count": 0.0, "1": 0.0}
#: KPIs whose tolerance is not their unit's: the battery's remaining share is read to 0.1 pp
ABS_TOL = {"battery_remaining": 1e-3}


def abs_tolerance(name: str) -> float:
    """The absolute tolerance of KPI ``name`` in its SI unit (0 for an unknown KPI)."""
    info = get(name)
    if info is None:
        return 0.0
    if info.abs_tol is not None:
        return float(info.abs_tol)
    tail = name.split(".")[-1]
    if tail in ABS_TOL or name in ABS_TOL:
        return ABS_TOL.get(name, ABS_TOL.get(tail, 0.0))
    return UNIT_ABS_TOL.get(info.unit, 0.0)


def get(name: str) -> KPI | None:
    """The KPI ``name``: built in, registered, a family member (``recall.person``),
    a task's own (``<task>.<kpi>``, e.g. ``cnn.recall.person``) or one drone's of a
    fleet (``<drone>.<any of those>``, e.g. ``d1.policy.team.time_confirm_s``)."""
    k = _resolve(name)
    if k is not None or not isinstance(name, str) or "." not in name:
        return k
    drone, rest = name.split(".", 1)
    if not drone or rest.startswith("fleet."):     # fleet-wide KPIs have no per-drone copy
        return None
    k = _resolve(rest)
    if k is None:
        return None
    return KPI(name, k.unit, k.better, f"drone {drone}: {k.description}", k.abs_tol)


def _resolve(name: str) -> KPI | None:
    """``get`` without the fleet drone prefix."""
    k = REGISTRY.get(name)
    if k is not None or not isinstance(name, str) or "." not in name:
        return k
    parts = name.split(".")
    for i in range(len(parts) - 1):
        head, rest = parts[i], parts[i + 1:]
        if head in FAMILIES and rest and all(rest):
            return KPI(name, "fraction", "higher", f"{REGISTRY[head].description} ({FAMILIES[head]})")
        tail = REGISTRY.get(".".join(parts[i + 1:]))
        if tail is not None and "." not in tail.name:
            return KPI(name, tail.unit, tail.better, f"task {'.'.join(parts[:i + 1])}: {tail.description}")
    return None


def names() -> list[str]:
    """Every KPI name known now (built in and registered), in table order."""
    return list(REGISTRY)


def register(name: str, unit: str = "1", better: str | None = None, description: str = "",
             abs_tol: float | None = None) -> KPI:
    """Register a custom KPI (e.g. a probe metric ``probe.metric``); ``abs_tol``: a
    change smaller than this is noise in comparisons (default: the unit's)."""
    if better not in ("higher", "lower", None):
        raise ConfigError(f"KPI {name!r}: better = {better!r} is not allowed; allowed: 'higher', 'lower', None")
    if abs_tol is not None and not (isinstance(abs_tol, (int, float)) and abs_tol >= 0):
        raise ConfigError(f"KPI {name!r}: abs_tol = {abs_tol!r} is not allowed; expected a "
                          f"number >= 0 (in the KPI's SI unit) or None")
    k = KPI(name, unit, better, description, None if abs_tol is None else float(abs_tol))
    old = REGISTRY.get(name)
    if old is not None and old != k and "." not in name:
        raise ConfigError(f"KPI {name!r} is built in; choose another name")
    REGISTRY[name] = k
    return k


# -- the one regression rule: the plugin's baseline gate and ``flockai compare`` both call it --
#: a relative change below this is float noise, whatever the KPI
NOISE_REL = 1e-6


def family(kpi: str) -> str:
    """The KPI with a task's or a drone's prefix taken off (``det.recall`` ->
    ``recall``, ``drone-2.flight_time_s`` -> ``flight_time_s``); registered names
    (``fleet.makespan_s``) and family members (``recall.person``) stay."""
    if kpi in BUILTIN or "." not in kpi:
        return kpi
    head, rest = kpi.split(".", 1)
    if head in FAMILIES:
        return kpi
    return family(rest) if get(rest) is not None else kpi


def tolerance(kpi: str, abs_tol: dict | None = None) -> float:
    """The absolute tolerance of ``kpi``: an override (by name or family), else the registry's."""
    over = abs_tol or {}
    if kpi in over:
        return float(over[kpi])
    if family(kpi) in over:
        return float(over[family(kpi)])
    return abs_tolerance(kpi)


def classify(kpi: str, base, new, threshold_pct: float,
             abs_tol: dict | None = None) -> tuple[str | None, str]:
    """(better direction, status) of one KPI from ``base`` to ``new``: "n/a" (missing or
    not finite), "same" (within the absolute tolerance or float noise), "changed" (no
    better direction), "better", "worse" (within ``threshold_pct`` percent of the base)
    or "regression". The plugin's baseline gate (``report.regressions``) and
    ``flockai compare`` (``reports.compare``) both decide with this function."""
    info = get(kpi)
    better = info.better if info is not None else None
    if base is None or new is None or not (math.isfinite(base) and math.isfinite(new)):
        return better, "n/a"
    noise = max(tolerance(kpi, abs_tol), NOISE_REL * max(abs(base), abs(new)))
    if abs(new - base) <= noise:
        return better, "same"
    if better is None:
        return better, "changed"
    worse = new < base if better == "higher" else new > base
    if not worse:
        return better, "better"
    tol = max(abs(base) * threshold_pct / 100.0, noise)
    return better, "regression" if abs(new - base) > tol else "worse"
