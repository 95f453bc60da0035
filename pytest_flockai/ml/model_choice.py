"""Would a cheaper model do? (the paper's Q4): several models on the same frames, one table.

``compare_models(models, path, flight=None, device="raspberry-pi-4", period_s=1.0,
runtimes=None)`` scores each model on the same labelled frames (``evaluate_dataset``: a
folder a flight recorded with ``Mission(dataset_dir=...)``, or a team's own), and puts
next to its accuracy what it costs on the drone's computer ``device``, one row per model
and runtime (``runtimes``: names, or (runtime, precision) pairs; None: the computer's
default runtime):

- ``latency_s``: the latency a flight charges (``ml.latency_model``: the layer model
  ``compute.predict_latency`` for an ONNX model, at the frames' size; the computer's
  MAC-count rule for a model known by its MAC count), with ``runtime``,
  ``runtime_precision`` (fp32/fp16/int8; ``precision`` is the detection KPI) and
  ``latency_model`` (``roofline`` or ``macs``) beside it;
- ``energy_per_inference_j``: that compute time at the device's busy-over-idle
  power (what ``<task>.compute_energy_j`` charges per inference);
- ``task_power_w``: one inference every ``period_s`` (at most back to back);
- ``endurance_s``: with ``flight`` (a FlightResult flown without the task), its
  ``endurance_s`` at its ``mean_power_w`` plus the task's power.
"""

from __future__ import annotations

import warnings

import cv2
import numpy as np
import pandas as pd

from ..compute.latency import resolve_device
from ..compute.predict import LatencyFallbackWarning, above_idle_w
from ..errors import ConfigError
from .dataset_eval import evaluate_dataset
from .latency_model import InferenceTimer
from .models import as_model
from .task import Task

ACCURACY = ("map50", "map50_95", "precision", "recall", "accuracy")


def compare_models(models: dict, path, *, flight=None, device="raspberry-pi-4",
                   period_s: float = 1.0, evaluate: str = "detection", runtimes=None,
                   **task_kw) -> pd.DataFrame:
    """One row per model of ``models`` ({name: model}) and runtime; see the module docstring."""
    if not isinstance(models, dict) or not models:
        raise ConfigError(f"compare_models: models = {models!r} is not allowed; expected a dict "
                          f"{{name: model}} of one or more models")
    dev = resolve_device(device, "device")
    deps = _deployments(runtimes)
    rows = []
    for name, model in models.items():
        task = Task(as_model(model), name=name, evaluate=evaluate, period_s=period_s, **task_kw)
        ev = evaluate_dataset(task, path)
        frame = _first_frame(ev)
        m = task.model
        macs = m.macs_for(frame) if hasattr(m, "macs_for") and frame is not None else m.macs
        if macs is None:
            raise ConfigError(f"compare_models: model {name!r} has macs = None; the modeled "
                              f"latency needs its MAC count: give the model macs=...")
        for runtime, precision in deps:
            with warnings.catch_warnings():     # the row's latency_model says which rule ran
                warnings.simplefilter("ignore", LatencyFallbackWarning)
                deployed = task.replace(runtime=runtime, precision=precision)
            timer = InferenceTimer(deployed, dev)
            lat = timer.seconds(m, frame if frame is not None else _blank(m), macs)
            e = lat * above_idle_w(dev, timer.deployment)
            power = e / max(period_s, lat)
            d = timer.describe()
            row = {"model": name, "runtime": d.get("runtime"),
                   "runtime_precision": d.get("precision"),
                   "latency_model": d["latency_model"], "macs": float(macs),
                   "params": getattr(m, "params", None),
                   **{k: ev.kpis[k] for k in ACCURACY if k in ev.kpis},
                   "images_scored": ev.kpis["images_scored"], "latency_s": lat,
                   "energy_per_inference_j": e, "task_power_w": power}
            if flight is not None:
                k = flight.kpis
                row["endurance_s"] = (k["endurance_s"] * k["mean_power_w"]
                                      / (k["mean_power_w"] + power))
            rows.append(row)
    return pd.DataFrame(rows)


def _deployments(runtimes) -> list:
    if runtimes is None:
        return [(None, None)]
    if isinstance(runtimes, str) or not isinstance(runtimes, (list, tuple)) or not runtimes:
        raise ConfigError(f"compare_models: runtimes = {runtimes!r} is not allowed; expected a "
                          f"list of runtime names or (runtime, precision) pairs")
    return [tuple(r) if isinstance(r, (list, tuple)) else (r, None) for r in runtimes]


def _blank(model):
    hw = getattr(model, "input_size", None) or (240, 320)
    return np.zeros((*hw, 3), np.uint8)


def _first_frame(ev):
    """The first scored image (RGB), for the MACs at the frames' size; None without one."""
    file = ev.records[0].file if ev.records else None
    img = cv2.imread(file, cv2.IMREAD_COLOR) if file else None
    return None if img is None else cv2.cvtColor(img, cv2.COLOR_BGR2RGB)


__all__ = ["compare_models"]
