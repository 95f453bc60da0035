"""ML tasks: what runs, on which sensor, how often, where, and how it is scored.

A ``Task`` is a validated description: a model, on which sensor, how often,
where (on board the drone or remotely on the ground station over a radio
link), and how its predictions are scored against the simulator's truth
(``evaluate``). ``ml.runner.TaskRunner`` executes it during a mission.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable, Sequence
from numbers import Integral
from typing import Any

from .. import _check, _io, limits
from ..comm.link import Link
from ..comm.link import link as _link
from ..compute import runtimes as _rt
from ..compute.devices import Device
from ..compute.latency import LATENCY_MODES, resolve_device
from ..compute.predict import LatencyFallbackWarning
from ..errors import ConfigError
from ..world.truth import CLASSES
from .detections import DECODERS
from .latency_model import graph_model
from .metrics import count_of
from .models import OnnxModel, as_model
from .templates import Template

EXECUTIONS = ("onboard", "remote")
ON_BUSY = ("drop", "queue")
ALERTS = ("frame", "result")
EVALUATIONS = ("count", "detection", "classification")


def _uses_dynamic_macs(model) -> bool:
    if isinstance(model, OnnxModel):
        return True
    return isinstance(model, Template) and model._macs_from_model


class Task:
    """An ML task: a validated description (see the module docstring).

    ``count``: ``prediction -> people count`` (default ``metrics.count_of``);
    ``crowd_threshold``: people count that makes a crowd (detection KPIs);
    ``ground_station``: (x, y, z) of the ground station, metres.

    ``device``: the on-board computer the task runs on. None (the default): the
    drone's own computer, from its blueprint's ``[compute] device``. A device
    other than the blueprint's is carried as a second computer: it is added,
    powered (its idle and active draw, in ``proc.soc``) and reported in the
    scenario's ``computers``, while the blueprint's computer keeps drawing its
    idle power (``proc.soc_blueprint``). To swap the computer instead, build the
    drone with it: ``fa.drone(name, device="jetson-orin-nano")``.

    ``evaluate``: how the predictions are scored against the truth:
    ``"count"`` (people counting: ``count_mae`` and crowd detection, the
    default), ``"detection"`` (boxes: COCO mAP, precision, recall, per class,
    altitude and size; see ``ml.evaluation``), ``"classification"`` (classes
    present in the frame), or a callable ``fn(records) -> {kpi: value}`` taking
    the ``evaluation.FrameRecord`` of every frame. ``classes``: the class names
    the model's class indices stand for (default: the worlds' ``person``,
    ``vehicle``); ``score_threshold``: detections (or class scores) at or above
    it count; ``iou_threshold``: NMS overlap for YOLO heads; ``decode``: how to
    read the model's output (``"auto"``, ``"boxes"``, ``"yolo"`` or a callable,
    see ``ml.detections``); ``min_visible``: objects less visible than this are
    ignore regions.

    ``runtime``, ``precision``, ``target``, ``threads``: the deployment on the computer the
    task runs on (``compute.runtimes``; defaults: the computer's first listed runtime and its
    usual precision; threads: every core). They set the latency of an ONNX model
    (``compute.predict_latency``); a computer that cannot run them is a ConfigError.
    """

    def __init__(self, model: Any, sensor: str = "camera", period_s: float = 5.0,
                 execution: str = "onboard", device: str | Device | None = None, *,
                 name: str | None = None, ground_device: str | Device = "ground-gpu",
                 link: str | Link = "wifi-80211n", on_busy: str = "drop",
                 latency: str = "modeled", result_bytes: int = 256, jpeg_quality: int = 90,
                 crowd_threshold: float = 10.0, count: Callable | None = None,
                 alert: str = "frame", ground_station: Sequence[float] = (0.0, 0.0, 0.0),
                 max_queue: int = 16, evaluate: str = "count", classes: Sequence[str] = CLASSES,
                 score_threshold: float = 0.25, iou_threshold: float = 0.5,
                 decode: str | Callable = "auto", min_visible: float = 0.25,
                 runtime: str | None = None, precision: str | None = None,
                 target: str | None = None, threads: int | None = None) -> None:
        self.model = as_model(model)
        self.name = name if name is not None else str(getattr(self.model, "name", "task"))
        if not isinstance(self.name, str) or not self.name or "." in self.name:
            raise ConfigError(f"Task: name = {self.name!r} is not allowed; expected a non-empty "
                              f"string without '.' (it prefixes KPI names)")
        where = f"task {self.name!r}"
        if not isinstance(sensor, str) or not sensor:
            raise ConfigError(f"{where}: sensor = {sensor!r} is not allowed; expected a sensor name "
                              f"such as 'camera'")
        self.sensor = sensor
        self.period_s = _check.positive("period_s", period_s, where=where)
        limits.check_at_least("period_s", self.period_s, "MIN_TASK_PERIOD_S", where=where,
                              unit=" s")
        self.execution = _check.choice("execution", execution, EXECUTIONS, where=where)
        if self.execution == "remote" and not getattr(self.model, "needs_pixels", True):
            raise ConfigError(f"{where}: execution = 'remote' is not allowed for model "
                              f"{self.name!r}: it reads the truth, not pixels, so there is no "
                              f"frame to send; model the transport as its delay_s instead")
        self.device = None if device is None else self._device("device", device, where)
        self.ground_device = self._device("ground_device", ground_device, where)
        self._deployment(where, runtime, precision, target, threads)
        try:
            self.link = _link(link)
        except ConfigError as e:
            raise ConfigError(f"{where}: {e}") from None
        self.on_busy = _check.choice("on_busy", on_busy, ON_BUSY, where=where)
        self.latency = _check.choice("latency", latency, LATENCY_MODES, where=where)
        self.result_bytes = self._int("result_bytes", result_bytes, where, 0)
        self.jpeg_quality = self._int("jpeg_quality", jpeg_quality, where, 0, 100)
        self.crowd_threshold = _check.positive("crowd_threshold", crowd_threshold, where=where)
        if count is not None and not callable(count):
            raise ConfigError(f"{where}: count = {count!r} is not callable; expected "
                              f"prediction -> people count")
        self.count = count or count_of
        self.alert = _check.choice("alert", alert, ALERTS, where=where)
        self.ground_station = _check.vector("ground_station", ground_station, 3, where=where)
        self.max_queue = self._int("max_queue", max_queue, where, 1)
        self._evaluation(where, evaluate, classes, score_threshold, iou_threshold, decode,
                         min_visible)
        if (self.latency == "modeled" and getattr(self.model, "macs", None) is None
                and not _uses_dynamic_macs(self.model)):
            raise ConfigError(f"{where}: model {self.name!r} has macs = None; latency='modeled' "
                              f"needs its MAC count: give the model macs=... or use "
                              f"latency='measured'")

    def _evaluation(self, where, evaluate, classes, score_threshold, iou_threshold, decode,
                    min_visible):
        if not (callable(evaluate) or evaluate in EVALUATIONS):
            raise ConfigError(f"{where}: evaluate = {evaluate!r} is not allowed; allowed: "
                              f"{', '.join(map(repr, EVALUATIONS))} or a callable fn(records)")
        self.evaluate = evaluate
        try:
            self.classes = tuple(str(c) for c in classes)
        except TypeError:
            raise ConfigError(f"{where}: classes = {classes!r} is not a list of class names") from None
        if not self.classes or len(set(self.classes)) != len(self.classes):
            raise ConfigError(f"{where}: classes = {classes!r} is not allowed; expected distinct names")
        self.score_threshold = _check.fraction("score_threshold", score_threshold, where=where)
        self.iou_threshold = _check.fraction("iou_threshold", iou_threshold, where=where)
        if not (callable(decode) or decode in DECODERS):
            raise ConfigError(f"{where}: decode = {decode!r} is not allowed; allowed: "
                              f"{', '.join(map(repr, DECODERS))} or a callable")
        self.decode = decode
        self.min_visible = _check.fraction("min_visible", min_visible, where=where)

    def _deployment(self, where, runtime, precision, target, threads):
        """The runtime/precision/target/threads: names checked now, and against the computer
        now when it is known (else when the flight binds the drone's)."""
        _rt.check_names(runtime, precision, target, threads, where=where)
        self.runtime, self.precision, self.target, self.threads = (runtime, precision, target,
                                                                   threads)
        dev = self.device if self.execution == "onboard" else self.ground_device
        if dev is not None and dev.deployments and dev.measured is None:
            _rt.resolve(dev, runtime, precision, target, threads,
                        where=f"{where} on {dev.name!r}")
        if (runtime, precision, target) != (None, None, None) and graph_model(self.model) is None:
            warnings.warn(f"{where}: runtime/precision/target given, but model {self.name!r} is "
                          f"known only by its MAC count: its latency uses the computer's "
                          f"MAC-count rule, whatever the runtime (give an ONNX model for the "
                          f"layer model)", LatencyFallbackWarning, stacklevel=3)

    @staticmethod
    def _device(field, value, where) -> Device:
        try:
            return resolve_device(value, field)
        except ConfigError as e:
            raise ConfigError(f"{where}: {e}") from None

    @staticmethod
    def _int(field, value, where, lo, hi=None) -> int:
        if isinstance(value, bool) or not isinstance(value, Integral) or value < lo or (
                hi is not None and value > hi):
            allowed = f"an int >= {lo}" + (f" and <= {hi}" if hi is not None else "")
            raise ConfigError(f"{where}: {field} = {value!r} is not allowed; expected {allowed}")
        return int(value)

    def to_dict(self) -> dict:
        """JSON-ready description for the flight's scenario."""
        m = self.model
        return {"name": self.name, "model": {"name": getattr(m, "name", None),
                                             "type": type(m).__name__,
                                             "macs": getattr(m, "macs", None),
                                             "params": getattr(m, "params", None),
                                             "sha256": model_sha256(m)},
                "sensor": self.sensor, "period_s": self.period_s, "execution": self.execution,
                "device": self.device.name if self.device is not None else None,
                "ground_device": self.ground_device.name,
                "link": self.link.name, "on_busy": self.on_busy, "latency": self.latency,
                "runtime": self.runtime, "precision": self.precision, "target": self.target,
                "threads": self.threads,
                "result_bytes": self.result_bytes, "jpeg_quality": self.jpeg_quality,
                "crowd_threshold": self.crowd_threshold, "alert": self.alert,
                "ground_station": list(self.ground_station), "max_queue": self.max_queue,
                "evaluate": self.evaluate if isinstance(self.evaluate, str) else
                getattr(self.evaluate, "__name__", repr(self.evaluate)),
                **({"classes": list(self.classes), "score_threshold": self.score_threshold,
                    "decode": self.decode if isinstance(self.decode, str) else "callable",
                    "min_visible": self.min_visible} if self.evaluate != "count" else {})}

    def __repr__(self):
        return (f"Task({self.name!r}, sensor={self.sensor!r}, period_s={self.period_s}, "
                f"execution={self.execution!r}, "
                f"device={self.device.name if self.device is not None else None!r})")


__all__ = ["ALERTS", "EVALUATIONS", "EXECUTIONS", "ON_BUSY", "Task"]


def model_sha256(model) -> str | None:
    """SHA-256 of a model's file (an ``OnnxModel``'s ``path``), memoised on the file's
    mtime and size; None for a model without a file. The reports name a model by it."""
    path = getattr(model, "path", None)
    if not isinstance(path, (str, os.PathLike)):
        return None
    try:
        return _io.file_digest(path)
    except OSError:
        return None

