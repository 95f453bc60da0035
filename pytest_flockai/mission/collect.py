"""Collect a flown (or failed) drone's ``Run`` into its FlightResult: KPIs from
the probes, telemetry with the probes' metrics and the camera truth merged in,
events, scenario. (The ``FlightResult`` class itself is ``pytest_flockai.result``.)"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..control.stages import DONE, PILOT
from ..result import FlightResult
from ..sensors import export_dataset


def flight_result(run, mission, wall_s: float, t_final: float, end_reason: str) -> FlightResult:
    """The FlightResult of ``run`` (a drone of ``mission``) ended at ``t_final``."""
    plan, st = run.plan, run.vehicle
    tel = run.telemetry.frame()
    d = run.data
    stage = DONE if st.t_land else PILOT
    kpis = run.probing.final(t_final, d.qpos.tolist(), d.qvel.tolist(), stage)
    kpis.update(run.scheduler.evaluation_kpis())
    for p in getattr(run, "policies", ()):
        kpis.update(p.kpis(run))
    kpis.update(run.scheduler.energy_kpis(run.meter))
    frames = run.hub.frames()
    _merge_probe_columns(tel, frames)
    scen = mission.scenario()
    scen["sim_time_s"] = float(t_final)
    scen["physics_hz"] = plan.drone.sim.physics_hz
    scen["control_hz"] = 1.0 / plan.ctrl_dt
    scen["controller_gains"] = run.controller.gains
    sched = run.scheduler
    events = sorted(run.events.items + run.hub.errors + sched.inference_events(),
                    key=lambda e: e["t"])
    if sched.in_view and len(tel):
        iv = pd.DataFrame(sched.in_view, columns=["t", "people_in_view", "blur_px"])
        merged = pd.merge_asof(tel[[]].reset_index(), iv.drop_duplicates("t"), on="t",
                               direction="nearest", tolerance=0.5 / plan.telemetry_hz)
        for c in ("people_in_view", "blur_px"):
            tel[c] = merged[c].to_numpy(dtype=float)
    if sched.recorder is not None and sched.recorder.records:
        export_dataset(sched.recorder.records, plan.dataset_dir)
    res = FlightResult(kpis, tel, events, scen, run.meter.breakdown(), end_reason, wall_s,
                       probe_samples=frames, probe_errors=list(run.hub.errors))
    res.ml_gallery = sched.galleries()          # the detection tasks' worst frames, drawn
    res.ml_coco = sched.coco_pairs()            # and their truth and predictions (COCO)
    res.policies = {p.name: p for p in getattr(run, "policies", ())}   # the flown copies
    w = plan.world
    res.people = np.asarray(w.people) if w is not None and hasattr(w, "people") else np.zeros((0, 3))
    return res


def _merge_probe_columns(tel, frames) -> None:
    """Probe metrics into the telemetry, as of each row."""
    for df in frames.values():
        extra = [c for c in df.columns if c not in tel.columns]
        if extra and len(df) and len(tel):
            merged = pd.merge_asof(tel[[]].reset_index(), df[extra].reset_index(), on="t",
                                   direction="backward")
            for c in extra:
                tel[c] = merged[c].to_numpy()
