"""ML tasks: what runs, on which sensor, how often, where, and how it is scored.

A ``Task`` is a validated description: a model, on which sensor, how often,
where (on board the drone or remotely on the ground station over a radio
link), and how its predictions are scored against the simulator's truth
(``evaluate``). ``ml.task_runner.TaskRunner`` executes it during a mission.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable, Sequence
from dataclasses import KW_ONLY, dataclass
from numbers import Integral
from typing import Any

from .. import _check, _io, limits
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


@dataclass(frozen=True, eq=False, repr=False)
class Task:
    """An ML task: a validated description (see the module docstring).

    A frozen spec like ``Mission``: every argument after ``model`` is keyword-only, all are
    checked here, and ``task.replace(**changes)`` returns a checked copy (assigning a field
    raises ``dataclasses.FrozenInstanceError``).

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
    usual precision; threads: the runtime's default, every core but for TF Lite's one). They
    set the latency of an ONNX model (``compute.predict_latency``); a computer that cannot
    run them is a ConfigError.
    """

    model: Any
    _: KW_ONLY
    sensor: str = "camera"
    period_s: float = 5.0
    execution: str = "onboard"
    # given as a name or an object, stored as the object (typed Any for that reason)
    device: Any = None                             # str | Device, stored as Device | None
    name: Any = None                               # str | None, stored as str (the model's)
    ground_device: Any = "ground-gpu"              # str | Device, stored as Device
    link: Any = "wifi-80211n"                      # str | Link, stored as Link
    on_busy: str = "drop"
    latency: str = "modeled"
    result_bytes: int = 256
    jpeg_quality: int = 90
    crowd_threshold: float = 10.0
    count: Callable | None = None                  # stored as the counting function
    alert: str = "frame"
    ground_station: Sequence[float] = (0.0, 0.0, 0.0)
    max_queue: int = 16
    evaluate: str | Callable = "count"
    classes: Sequence[str] = CLASSES               # stored as a tuple
    score_threshold: float = 0.25
    iou_threshold: float = 0.5
    decode: str | Callable = "auto"
    min_visible: float = 0.25
    runtime: str | None = None
    precision: str | None = None
    target: str | None = None
    threads: int | None = None

    def __post_init__(self) -> None:
        put = object.__setattr__         # the checked, normalized value of a frozen field
        put(self, "model", as_model(self.model))
        name = self.name if self.name is not None else str(getattr(self.model, "name", "task"))
        if not isinstance(name, str) or not name or "." in name:
            raise ConfigError(f"Task: name = {name!r} is not allowed; expected a non-empty "
                              f"string without '.' (it prefixes KPI names)")
        put(self, "name", name)
        where = f"task {name!r}"
        if not isinstance(self.sensor, str) or not self.sensor:
            raise ConfigError(f"{where}: sensor = {self.sensor!r} is not allowed; expected a "
                              f"sensor name such as 'camera'")
        put(self, "period_s", _check.positive("period_s", self.period_s, where=where))
        limits.check_at_least("period_s", self.period_s, "MIN_TASK_PERIOD_S", where=where,
                              unit=" s")
        put(self, "execution", _check.choice("execution", self.execution, EXECUTIONS, where=where))
        if self.execution == "remote" and not getattr(self.model, "needs_pixels", True):
            raise ConfigError(f"{where}: execution = 'remote' is not allowed for model "
                              f"{name!r}: it reads the truth, not pixels, so there is no "
                              f"frame to send; model the transport as its delay_s instead")
        if self.device is not None:
            put(self, "device", self._device("device", self.device, where))
        put(self, "ground_device", self._device("ground_device", self.ground_device, where))
        self._deployment(where)
        try:
            put(self, "link", _link(self.link))
        except ConfigError as e:
            raise ConfigError(f"{where}: {e}") from None
        put(self, "on_busy", _check.choice("on_busy", self.on_busy, ON_BUSY, where=where))
        put(self, "latency", _check.choice("latency", self.latency, LATENCY_MODES, where=where))
        put(self, "result_bytes", self._int("result_bytes", self.result_bytes, where, 0))
        put(self, "jpeg_quality", self._int("jpeg_quality", self.jpeg_quality, where, 0, 100))
        put(self, "crowd_threshold", _check.positive("crowd_threshold", self.crowd_threshold,
                                                     where=where))
        if self.count is not None and not callable(self.count):
            raise ConfigError(f"{where}: count = {self.count!r} is not callable; expected "
                              f"prediction -> people count")
        put(self, "count", self.count or count_of)
        put(self, "alert", _check.choice("alert", self.alert, ALERTS, where=where))
        put(self, "ground_station", _check.vector("ground_station", self.ground_station, 3,
                                                  where=where))
        put(self, "max_queue", self._int("max_queue", self.max_queue, where, 1))
        self._evaluation(where)
        if (self.latency == "modeled" and getattr(self.model, "macs", None) is None
                and not _uses_dynamic_macs(self.model)):
            raise ConfigError(f"{where}: model {name!r} has macs = None; latency='modeled' "
                              f"needs its MAC count: give the model macs=... or use "
                              f"latency='measured'")

    def replace(self, **changes) -> Task:
        """A copy with ``changes`` (field=value), checked again like a new Task
        (``dataclasses.replace``). The name stays the one resolved here unless changed."""
        return _check.replace(self, "Task", changes)

    def _evaluation(self, where) -> None:
        put = object.__setattr__
        evaluate, classes, decode = self.evaluate, self.classes, self.decode
        if not (callable(evaluate) or evaluate in EVALUATIONS):
            raise ConfigError(f"{where}: evaluate = {evaluate!r} is not allowed; allowed: "
                              f"{', '.join(map(repr, EVALUATIONS))} or a callable fn(records)")
        try:
            put(self, "classes", tuple(str(c) for c in classes))
        except TypeError:
            raise ConfigError(f"{where}: classes = {classes!r} is not a list of class names") from None
        if not self.classes or len(set(self.classes)) != len(self.classes):
            raise ConfigError(f"{where}: classes = {classes!r} is not allowed; expected distinct names")
        for f in ("score_threshold", "iou_threshold", "min_visible"):
            put(self, f, _check.fraction(f, getattr(self, f), where=where))
        if not (callable(decode) or decode in DECODERS):
            raise ConfigError(f"{where}: decode = {decode!r} is not allowed; allowed: "
                              f"{', '.join(map(repr, DECODERS))} or a callable")

    def _deployment(self, where) -> None:
        """The runtime/precision/target/threads: names checked now, and against the computer
        now when it is known (else when the flight binds the drone's)."""
        runtime, precision, target, threads = self.runtime, self.precision, self.target, self.threads
        _rt.check_names(runtime, precision, target, threads, where=where)
        dev = self.device if self.execution == "onboard" else self.ground_device
        if dev is not None and dev.deployments and dev.measured is None:
            _rt.resolve(dev, runtime, precision, target, threads,
                        where=f"{where} on {dev.name!r}")
        if (runtime, precision, target) != (None, None, None) and graph_model(self.model) is None:
            warnings.warn(f"{where}: runtime/precision/target given, but model {self.name!r} is "
                          f"known only by its MAC count: its latency uses the computer's "
                          f"MAC-count rule, whatever the runtime (give an ONNX model for the "
                          f"layer model)", LatencyFallbackWarning, stacklevel=4)

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

