"""Detector outputs parsed into one shape: ``Detections`` (boxes, scores, classes).

What a detection task's model may return (``parse_detections``):

- an array (N, 6) ``x0, y0, x1, y1, score, class`` (also (1, N, 6)); boxes in
  pixels, or normalised to [0, 1] of the frame (``normalized=True``; None: auto,
  normalised when every coordinate is within [0, 1.5]);
- a dict with ``boxes`` (N, 4), ``scores`` (N,) and ``classes`` / ``labels`` (N,)
  (torchvision style), or a tuple ``(boxes, scores, classes)``;
- a YOLO raw head, decoded here (``decode="yolo"``, or auto from its shape):
  YOLOv8 layout (1, 4 + C, A): rows ``cx, cy, w, h`` then one score per class,
  for A anchors; YOLOv5 layout (1, A, 5 + C): ``cx, cy, w, h, objectness`` then
  class scores (score = objectness x class score). Boxes in input pixels of the
  model (scaled to the frame when the model resized it: ``input_hw``). Each
  anchor's best class is kept when its score reaches ``score_threshold``, then
  OpenCV's ``cv2.dnn.NMSBoxesBatched`` removes overlaps per class
  (``iou_threshold``);
- anything else through ``decode=callable(prediction, frame_hw) -> Detections
  or (N, 6)``.

A shape that fits none of these raises a ``ConfigError`` naming the task, the
shape received and what is expected.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from ..errors import ConfigError

DECODERS = ("auto", "boxes", "yolo")


@dataclass
class Detections:
    boxes: np.ndarray        # (M, 4) float x0, y0, x1, y1 in frame pixels
    scores: np.ndarray       # (M,)
    cls: np.ndarray          # (M,) int class index

    def __len__(self) -> int:
        return int(len(self.scores))

    @classmethod
    def empty(cls) -> Detections:
        """No detections."""
        return cls(np.zeros((0, 4)), np.zeros(0), np.zeros(0, dtype=int))

    def above(self, threshold: float) -> Detections:
        """The detections scoring at least ``threshold``."""
        keep = self.scores >= threshold
        return Detections(self.boxes[keep], self.scores[keep], self.cls[keep])


def parse_detections(pred, frame_hw, *, n_classes: int, where: str, decode="auto",
                     normalized=None, score_threshold: float = 0.25, iou_threshold: float = 0.5,
                     input_hw=None) -> Detections:
    """A model's prediction as ``Detections`` in frame pixels (see the module docstring)."""
    if callable(decode):
        out = decode(pred, tuple(frame_hw))
        if isinstance(out, Detections):
            return _checked(out, n_classes, where)
        return _from_rows(np.asarray(out, dtype=float), frame_hw, False, n_classes, where)
    if isinstance(pred, Detections):
        return _checked(pred, n_classes, where)
    if isinstance(pred, dict):
        return _from_parts(pred.get("boxes"), pred.get("scores"),
                           pred.get("classes", pred.get("labels")), frame_hw, normalized,
                           n_classes, where)
    if isinstance(pred, (tuple, list)) and len(pred) == 3 and not np.isscalar(pred[0]):
        boxes, scores, classes = pred
        return _from_parts(boxes, scores, classes, frame_hw, normalized, n_classes, where)
    try:
        a = np.asarray(pred, dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(f"{where}: the model returned {type(pred).__name__}; a detection task "
                          f"expects an (N, 6) array, a dict of boxes/scores/classes or a YOLO "
                          f"raw head (or give decode=)") from None
    if a.ndim == 3 and a.shape[0] == 1:
        a = a[0]
    if decode == "yolo" or (decode == "auto" and a.ndim == 2 and a.shape[1] != 6
                            and _yolo_layout(a, n_classes) is not None):
        return _yolo(a, frame_hw, input_hw, n_classes, score_threshold, iou_threshold, where)
    if a.ndim == 2 and a.shape[1] == 6 or a.size == 0:
        return _from_rows(a.reshape(-1, 6), frame_hw, normalized, n_classes, where)
    raise ConfigError(f"{where}: the model returned shape {tuple(np.shape(pred))}; a detection "
                      f"task expects (N, 6) rows x0 y0 x1 y1 score class, a YOLOv8 head "
                      f"(1, 4+{n_classes}, anchors), a YOLOv5 head (1, anchors, 5+{n_classes}), "
                      f"or decode=")


def _yolo_layout(a, nc):
    if a.ndim != 2:
        return None
    if a.shape[0] == 4 + nc:
        return "v8"
    if a.shape[1] == 5 + nc:
        return "v5"
    return None


def _yolo(a, frame_hw, input_hw, nc, thr, iou, where) -> Detections:
    layout = _yolo_layout(a, nc)
    if layout is None:
        raise ConfigError(f"{where}: decode='yolo' got shape {a.shape}; expected (4+{nc}, anchors) "
                          f"(YOLOv8) or (anchors, 5+{nc}) (YOLOv5) for {nc} classes")
    if layout == "v8":
        xywh, cls_scores = a[:4].T, a[4:].T
    else:
        xywh, cls_scores = a[:, :4], a[:, 5:] * a[:, 4:5]
    cls = cls_scores.argmax(axis=1)
    score = cls_scores[np.arange(len(cls)), cls]
    keep = np.flatnonzero(score >= thr)
    if len(keep) == 0:
        return Detections.empty()
    xywh, score, cls = xywh[keep], score[keep], cls[keep]
    sx = sy = 1.0
    if input_hw is not None:
        sy, sx = frame_hw[0] / input_hw[0], frame_hw[1] / input_hw[1]
    boxes = np.column_stack([(xywh[:, 0] - xywh[:, 2] / 2) * sx, (xywh[:, 1] - xywh[:, 3] / 2) * sy,
                             (xywh[:, 0] + xywh[:, 2] / 2) * sx, (xywh[:, 1] + xywh[:, 3] / 2) * sy])
    tl_wh = np.column_stack([boxes[:, :2], boxes[:, 2:] - boxes[:, :2]])
    kept = cv2.dnn.NMSBoxesBatched(tl_wh.tolist(), score.tolist(), cls.tolist(), float(thr), float(iou))
    idx = np.asarray(kept, dtype=int).reshape(-1)
    return Detections(boxes[idx], score[idx], cls[idx].astype(int))


def _from_parts(boxes, scores, classes, frame_hw, normalized, nc, where) -> Detections:
    if boxes is None or scores is None or classes is None:
        raise ConfigError(f"{where}: a detection dict needs 'boxes', 'scores' and 'classes' "
                          f"(or 'labels')")
    b = np.asarray(boxes, dtype=float).reshape(-1, 4)
    s = np.asarray(scores, dtype=float).reshape(-1)
    c = np.asarray(classes, dtype=float).reshape(-1)
    if not len(b) == len(s) == len(c):
        raise ConfigError(f"{where}: boxes {b.shape}, scores {s.shape} and classes {c.shape} "
                          f"differ in length")
    return _from_rows(np.column_stack([b, s, c]), frame_hw, normalized, nc, where)


def _from_rows(a, frame_hw, normalized, nc, where) -> Detections:
    if a.ndim != 2 or a.shape[1] != 6:
        raise ConfigError(f"{where}: detections have shape {a.shape}; expected (N, 6) rows "
                          f"x0 y0 x1 y1 score class")
    if len(a) and not np.isfinite(a).all():
        raise ConfigError(f"{where}: detections hold NaN or infinite values")
    boxes = a[:, :4].copy()
    if normalized is None:
        normalized = len(a) > 0 and boxes.max() <= 1.5 and boxes.min() >= -0.5
    if normalized:
        h, w = frame_hw
        boxes *= (w, h, w, h)
    return _checked(Detections(boxes, a[:, 4].copy(), a[:, 5].astype(int)), nc, where)


def _checked(d: Detections, nc, where) -> Detections:
    if len(d) and ((d.cls < 0).any() or (d.cls >= nc).any()):
        bad = int(d.cls[(d.cls < 0) | (d.cls >= nc)][0])
        raise ConfigError(f"{where}: detection class {bad} is unknown; allowed: 0..{nc - 1}")
    return d
