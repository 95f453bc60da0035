"""Dataset mode, offline: a task's model over a labelled folder, every image exactly once.

``evaluate_dataset(task, path)`` reads the folder as ``sensors.ReplayCamera`` does
(COCO, YOLO flat or images/ + labels/, an Ultralytics data.yaml, VisDrone-DET;
``annotations``, ``split`` and ``classes`` as there), runs the task's model on each
image in file-name order, and scores the predictions with the same code as a flight
(``scoring.Scorer``: the same parsing, class matching by name, COCOeval). No
flight, no clock, no radio: a team's accuracy on its own data, before it flies.

It returns a ``DatasetEvaluation``: ``kpis`` (the task's accuracy KPIs plus
``images_scored`` and ``inference_failures``), ``records`` (one
``evaluation.FrameRecord`` per image, with its file), ``analysis()`` (PR curves,
per-class AP, confusion matrix, F1-best threshold: ``ml.analysis``) and
``write_results(path)`` (the predictions as a COCO results file).
"""

from __future__ import annotations

import math
import os

from ..errors import ConfigError
from ..sensors.replay import ReplayCamera
from .analysis import analyse, write_coco_pair
from .events import InferenceEvent
from .gallery import worst_frames
from .metrics import invalid_prediction
from .task import Task
from .task_scoring import Scorer


class DatasetEvaluation:
    """The outcome of ``evaluate_dataset`` (see the module docstring)."""

    def __init__(self, task: Task, path: str, records: list, kpis: dict, failures: list):
        self.task, self.path, self.records, self.kpis = task, path, records, kpis
        self.failures = failures            # (file, error) per failed inference

    def analysis(self) -> dict:
        """PR curves, per-class AP, confusion matrix and F1-best threshold (``ml.analysis``)."""
        return analyse(self.records, self.task.classes, min_visible=self.task.min_visible,
                       score_threshold=self.task.score_threshold)

    def gallery(self, n: int = 6) -> list:
        """The ``n`` images with the most mistakes, drawn (``ml.gallery.worst_frames``)."""
        return worst_frames(self.records, self.task, n)

    def write_results(self, folder) -> dict:
        """``<task>.truth.json`` and ``<task>.results.json`` (COCO ground truth and
        predictions) in ``folder``; returns their paths."""
        return write_coco_pair(self.records, self.task.classes, folder, self.task.name,
                               min_visible=self.task.min_visible)

    def __repr__(self):
        return (f"DatasetEvaluation({self.task.name!r}, {self.path!r}, "
                f"images_scored={self.kpis.get('images_scored')})")


def evaluate_dataset(task: Task, path, *, annotations="auto", split=None, classes=None,
                     altitude_m: float = math.nan) -> DatasetEvaluation:
    """Run ``task``'s model once over every image of ``path`` and score it offline.
    ``altitude_m``: the altitude the frames were taken at, for the altitude bands."""
    if not isinstance(task, Task):
        raise ConfigError(f"evaluate_dataset: task = {task!r} is not allowed; expected an "
                          f"fa.Task(model, evaluate='detection' or 'classification', ...)")
    if task.evaluate == "count":
        raise ConfigError(f"evaluate_dataset: task {task.name!r} has evaluate='count'; dataset "
                          f"scoring needs evaluate='detection', 'classification' or a callable")
    try:
        cam = ReplayCamera(path, rate_hz=1.0, loop=False, annotations=annotations, split=split,
                           classes=classes, name=task.sensor)
    except ConfigError as exc:    # say which call read the folder, not only the camera
        raise ConfigError(f"evaluate_dataset(task {task.name!r}): {exc}") from None
    if cam.files is None or cam._truth is None:
        raise ConfigError(f"evaluate_dataset: {os.fspath(path)!r} has no labels to score "
                          f"against (COCO, YOLO or VisDrone-DET)")
    scorer = Scorer(task)
    failures: list = []
    for k in range(len(cam.files)):          # n_frames of an image folder
        frame = cam.read(float(k))
        _score_one(task, scorer, k, frame, cam.last_truth, altitude_m, failures, cam.files[k])
    if failures and len(failures) == cam.n_frames:     # a setting, not the data: say which
        raise ConfigError(f"evaluate_dataset(task {task.name!r}): the model failed on every one of "
                          f"the {cam.n_frames} image(s); the first, {failures[0][0]!r}: "
                          f"{failures[0][1]}")
    kpis = {"images_scored": 0.0, **scorer.evaluation()}
    kpis["inference_failures"] = float(len(failures))
    recs = [scorer.records[k] for k in sorted(scorer.records)]
    return DatasetEvaluation(task, os.fspath(path), recs, kpis, failures)


def _score_one(task, scorer, k, frame, truth, altitude_m, failures, file):
    scorer.frame(k, frame, truth, (0.0, 0.0, altitude_m), float(k))
    pred = err = count = None
    try:
        pred = task.model(frame)
    except Exception as e:  # a failed inference, as in flight
        err = f"{type(e).__name__}: {e}"
    if err is None:
        count = scorer.count(pred, k, frame)
        err = invalid_prediction(pred, count, task, scorer.parse_error)
    if err is not None:
        failures.append((file, err))
    scorer.finished(InferenceEvent(task=task.name, frame_index=k, t_capture=float(k),
                                   prediction=pred, count=count, ok=err is None, error=err))
