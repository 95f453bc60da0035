"""How one task's predictions are scored against the frames' truth.

``Scorer`` keeps, per frame the task took, the truth (the people count, and for
detection and classification tasks the frame's ``FrameRecord`` with its truth
objects), and per finished inference the prediction: a count, parsed
``Detections``, or the raw output for classification and custom evaluators.
Counting KPIs are live (``count_kpis``); the others are computed once, at the
end of the flight (``evaluation``). Dropped frames are not scored; a failed
inference scores as a frame where nothing was found.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import ConfigError
from ..sensors.classnames import to_task_classes
from .detections import Detections, parse_detections
from .evaluation import FrameRecord, classification_kpis, detection_kpis
from .jpeg import encode_jpeg, is_image
from .metrics import crowd_metrics, truth_count

#: JPEG quality of the rendered frames a detection task keeps for its gallery
GALLERY_JPEG_QUALITY = 85


class Scorer:
    def __init__(self, task):
        self.task = task
        self.truth: list[float] = []        # people in view per frame (NaN: unknown)
        self.pred: list[float] = []         # predicted count per frame (NaN: none)
        self.records: dict = {}             # frame index -> FrameRecord
        self._dets: dict = {}               # frame index -> Detections parsed for the count
        self.parse_error: str | None = None  # why the last prediction could not be parsed
        self._maps: dict = {}               # the labels' class names -> the task's, by name

    def frame(self, idx: int, frame, truth, drone_pos, t: float = math.nan) -> float | None:
        """A frame the task took; returns its true people count (None: unknown)."""
        tc = truth_count(truth)
        self.truth.append(math.nan if tc is None else tc)
        self.pred.append(math.nan)
        if self.task.evaluate != "count" and hasattr(truth, "objects"):
            shape = np.shape(frame)
            tk = self.task
            objs = to_task_classes(truth.objects, tk.classes, f"task {tk.name!r}", self._maps)
            blur = getattr(truth, "blur_px", (0.0, 0.0))
            self.records[idx] = FrameRecord(idx, objs, None, float(drone_pos[2]),
                                            int(shape[1]) if len(shape) > 1 else 0,
                                            int(shape[0]) if len(shape) else 0,
                                            file=getattr(truth, "file", None),
                                            blur_px=float(np.hypot(*blur)), t=float(t))
            if tk.evaluate == "detection" and self.records[idx].file is None and is_image(frame):
                self.records[idx].image = encode_jpeg(frame, GALLERY_JPEG_QUALITY)
        return tc

    def count(self, pred, idx, frame):
        """The people count of a prediction; for a detection task, the person
        detections at the score threshold (parsed once, kept for scoring)."""
        t = self.task
        self.parse_error = None
        if t.evaluate == "detection":
            try:
                dets = self._parse(pred, np.shape(frame)[:2])
            except ConfigError as exc:      # one bad output: a failed inference, not a crash
                self.parse_error = str(exc)
                return None
            self._dets[idx] = dets
            sel = dets.above(t.score_threshold)
            if "person" in t.classes:
                return float((sel.cls == t.classes.index("person")).sum())
            return float(len(sel))
        try:
            return t.count(pred)
        except Exception:
            return None

    def finished(self, ev) -> None:
        """A finished inference: its count, and its prediction for its frame's record."""
        if ev.ok and ev.count is not None:
            self.pred[ev.frame_index] = ev.count
        rec = self.records.get(ev.frame_index)
        if rec is None:
            return
        t = self.task
        rec.prediction = ev.prediction if ev.ok else None
        if t.evaluate == "detection" or (callable(t.evaluate) and t.decode != "auto"):
            if not ev.ok:
                rec.detections = Detections.empty()        # a failed inference found nothing
                return
            rec.detections = self._dets.pop(ev.frame_index, None)
            if rec.detections is None:
                rec.detections = self._parse(ev.prediction, (rec.height, rec.width))

    def _parse(self, pred, frame_hw) -> Detections:
        t = self.task
        return parse_detections(pred, frame_hw, n_classes=len(t.classes), where=f"task {t.name!r}",
                                decode=t.decode, score_threshold=t.score_threshold,
                                iou_threshold=t.iou_threshold,
                                input_hw=getattr(t.model, "input_size", None))

    def crowd(self) -> dict | None:
        """Crowd counting metrics (``metrics.crowd_metrics``), or None without truth."""
        if not any(not math.isnan(x) for x in self.truth):
            return None
        return crowd_metrics(self.truth, self.pred, self.task.crowd_threshold)

    def count_kpis(self) -> dict:
        m = self.crowd() if self.task.evaluate == "count" else None
        if m is None:
            return {}
        return {k: m[k] for k in ("count_mae", "detection_precision", "detection_recall",
                                  "detection_delay_frames")}

    def evaluation(self) -> dict:
        """The accuracy KPIs of a detection, classification or custom evaluation
        ({} for counting tasks: theirs are live, in ``count_kpis``)."""
        t = self.task
        if t.evaluate == "count":
            return {}
        recs = [self.records[k] for k in sorted(self.records)
                if self.records[k].prediction is not None or self.records[k].detections is not None]
        if callable(t.evaluate):
            out = {str(k): float(v) for k, v in (t.evaluate(recs) or {}).items()}
        elif t.evaluate == "detection":
            out = detection_kpis(recs, t.classes, score_threshold=t.score_threshold,
                                 min_visible=t.min_visible)
        else:
            out = classification_kpis(recs, t.classes, score_threshold=t.score_threshold,
                                      min_visible=t.min_visible, where=f"task {t.name!r}")
        return {**out, "images_scored": float(len(recs))} if recs else out
