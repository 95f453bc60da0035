"""Accuracy of detection and classification tasks, against the simulator's truth.

Detection metrics follow the COCO standard and are computed by pycocotools'
``COCOeval`` (the reference implementation), fed in memory with one image per
frame the task saw:

- ``map50``, ``map50_95``: mean average precision over the classes at IoU 0.5,
  and averaged over IoU 0.50:0.05:0.95 (COCO's 101-point interpolation; up to
  1000 detections per frame, since crowds hold more than COCO's default 100);
  per class ``map50.<class>``;
- ``precision``, ``recall`` at the task's ``score_threshold``: the detections
  scoring at least the threshold, matched to the truth greedily by score at
  IoU >= 0.5 (COCOeval's own matching), per class ``recall.<class>`` and
  ``precision.<class>``;
- ``recall.alt_<lo>_<hi>m``: recall by the drone's altitude when the frame was
  taken (bands ``ALTITUDE_BANDS_M``); ``recall.size_<band>``: by the object's
  box height in pixels (``SIZE_BANDS_PX``: COCO's small/medium/large split at
  32 and 96 px is too coarse for aerial frames, where a person is 3-20 px);
- ``detection_delay_frames``: the paper's Table 4 "inference delay" carried
  to objects: for each object (by its world id) the number of the task's
  frames from its first appearance to its first detection, averaged over the
  objects that were detected; ``objects_missed``: the fraction never detected.

Truth objects whose visible fraction is below ``min_visible`` are ignore
regions (COCO ``iscrowd``): finding them is not rewarded, missing them is not
punished, and a detection on them is not a false positive.

Classification (``evaluate="classification"``): multi-label presence per
frame. The truth is the set of classes in view (visible >= ``min_visible``);
the prediction is a score per class (labels at >= ``score_threshold``), a
class name, or a list of names. KPIs: ``accuracy`` (frames whose label set is
exactly right), ``precision.<class>``, ``recall.<class>``.
"""

from __future__ import annotations

import contextlib
import io
import math
import os
from dataclasses import dataclass

import numpy as np
from pycocotools.coco import COCO
from pycocotools.cocoeval import COCOeval

from .. import memo
from ..errors import ConfigError
from .detections import Detections

ALTITUDE_BANDS_M = ((0.0, 20.0), (20.0, 40.0), (40.0, 60.0), (60.0, math.inf))
SIZE_BANDS_PX = ((0.0, 8.0), (8.0, 16.0), (16.0, 32.0), (32.0, math.inf))
MAX_DETS = (10, 100, 1000)


@dataclass
class FrameRecord:
    """One frame a task scored: its truth objects, what the model found (None:
    the inference failed or the frame was dropped), the drone's altitude and the
    frame size; ``prediction`` is the raw model output (custom evaluators);
    ``file``: the replayed image (None: rendered); ``blur_px``: the frame's motion
    blur length; ``t``: the capture time."""

    index: int
    truth: object                  # world.truth.Objects
    detections: Detections | None
    altitude_m: float
    width: int
    height: int
    prediction: object = None
    file: str | None = None
    blur_px: float = 0.0
    t: float = math.nan
    image: bytes | None = None       # a rendered frame as JPEG (the gallery draws it)


def _band(lo, hi, unit):
    return f"ge{lo:g}{unit}" if math.isinf(hi) else (f"lt{hi:g}{unit}" if lo == 0 and unit == "px"
                                                    else f"{lo:g}_{hi:g}{unit}")


def detection_kpis(records, classes, *, score_threshold: float, min_visible: float) -> dict:
    """The detection KPIs of ``records`` (frames whose inference ran); memoised
    (``pytest_flockai.memo``) on what COCOeval reads of them."""
    recs = [r for r in records if r.detections is not None]
    if not recs:
        return {}
    inputs = {"records": [(r.index, r.truth, r.detections, r.altitude_m, r.width, r.height)
                          for r in recs],
              "classes": list(classes), "score_threshold": score_threshold,
              "min_visible": min_visible}
    return memo.recall("detection-kpis", inputs,
                       lambda: _detection_kpis(recs, classes, score_threshold, min_visible),
                       pack=dict, unpack=dict)


def _detection_kpis(recs, classes, score_threshold: float, min_visible: float) -> dict:
    ev, gt, dts, info = run_cocoeval(recs, classes, min_visible)
    if ev is None:
        return {"map50": math.nan, "map50_95": math.nan, "recall": math.nan,
                "precision": _precision_without_truth(recs, score_threshold)}
    out = _average_precision(ev, classes)
    out.update(_at_threshold(ev, recs, classes, info, dts, score_threshold))
    return out


def run_cocoeval(recs, classes, min_visible: float, *, use_cats: bool = True):
    """(COCOeval evaluated and accumulated, ground truth dict, detections list, info per
    annotation id) of frames whose inference ran; (None, gt, dts, info) without truth.
    ``use_cats=False``: class-agnostic matching (a confusion matrix's)."""
    gt, dts, info = _coco_inputs(recs, classes, min_visible)
    if not gt["annotations"]:
        return None, gt, dts, info
    with contextlib.redirect_stdout(io.StringIO()):      # pycocotools prints progress
        coco_gt = COCO()
        coco_gt.dataset = gt
        coco_gt.createIndex()
        coco_dt = coco_gt.loadRes(dts) if dts else COCO()
        if not dts:
            coco_dt.dataset = {"images": gt["images"], "categories": gt["categories"],
                               "annotations": []}
            coco_dt.createIndex()
        ev = COCOeval(coco_gt, coco_dt, "bbox")
        ev.params.maxDets = list(MAX_DETS)
        ev.params.areaRng, ev.params.areaRngLbl = [[0, 1e10]], ["all"]
        ev.params.useCats = int(use_cats)
        ev.evaluate()
        ev.accumulate()
    return ev, gt, dts, info


def _coco_inputs(recs, classes, min_visible):
    images, anns, dts, info = [], [], [], {}
    for r in recs:
        iid = r.index + 1
        images.append({"id": iid, "width": int(r.width), "height": int(r.height),
                       "file_name": os.path.basename(r.file) if r.file else f"frame_{r.index:05d}"})
        o = r.truth
        for j in range(len(o) if o is not None else 0):
            x0, y0, x1, y1 = (float(v) for v in o.boxes[j])
            aid = len(anns) + 1
            hidden = bool(o.visible[j] < min_visible)
            anns.append({"id": aid, "image_id": iid, "category_id": int(o.cls[j]) + 1,
                         "bbox": [x0, y0, x1 - x0, y1 - y0], "area": (x1 - x0) * (y1 - y0),
                         "iscrowd": int(hidden)})
            info[aid] = (r.index, int(o.ids[j]), r.altitude_m, y1 - y0, hidden)
        d = r.detections
        for j in range(len(d)):
            x0, y0, x1, y1 = (float(v) for v in d.boxes[j])
            dts.append({"image_id": iid, "category_id": int(d.cls[j]) + 1,
                        "bbox": [x0, y0, max(x1 - x0, 1e-6), max(y1 - y0, 1e-6)],
                        "score": float(d.scores[j])})
    cats = [{"id": k + 1, "name": c} for k, c in enumerate(classes)]
    return {"images": images, "annotations": anns, "categories": cats}, dts, info


def _average_precision(ev, classes) -> dict:
    p = ev.eval["precision"][:, :, :, 0, -1]              # [iou, recall, class]
    out = {}
    per50, per_all = [], []
    for k, c in enumerate(classes):
        a50, aall = p[0, :, k], p[:, :, k]
        if (a50 > -1).any():
            v50 = float(a50[a50 > -1].mean())
            vall = float(aall[aall > -1].mean())
            out[f"map50.{c}"] = v50
            per50.append(v50)
            per_all.append(vall)
    out["map50"] = float(np.mean(per50)) if per50 else math.nan
    out["map50_95"] = float(np.mean(per_all)) if per_all else math.nan
    return out


def _at_threshold(ev, recs, classes, info, dts, thr) -> dict:
    """Precision and recall at the score threshold from COCOeval's matches at IoU 0.5."""
    score_of = {i + 1: d["score"] for i, d in enumerate(dts)}
    tp = np.zeros(len(classes))
    fp = np.zeros(len(classes))
    found: dict = {}                                        # annotation id -> matched
    for e in ev.evalImgs:
        if e is None or e["aRng"] != [0, 1e10] or e["maxDet"] != MAX_DETS[-1]:
            continue
        k = e["category_id"] - 1
        for j, did in enumerate(e["dtIds"]):
            if score_of[did] < thr or e["dtIgnore"][0, j]:
                continue
            if e["dtMatches"][0, j] > 0:
                tp[k] += 1
            else:
                fp[k] += 1
        for g, gid in enumerate(e["gtIds"]):
            if not e["gtIgnore"][g]:
                m = int(e["gtMatches"][0, g])
                found[gid] = m > 0 and score_of[m] >= thr
    out = {"precision": _ratio(tp.sum(), tp.sum() + fp.sum())}
    for k, c in enumerate(classes):
        if tp[k] + fp[k] > 0:
            out[f"precision.{c}"] = _ratio(tp[k], tp[k] + fp[k])
    rows = [(info[g], hit) for g, hit in found.items()]
    out["recall"] = _ratio(sum(h for _, h in rows), len(rows)) if rows else math.nan
    cls_of = {a["id"]: a["category_id"] - 1 for a in ev.cocoGt.dataset["annotations"]}
    for k, c in enumerate(classes):
        sel = [h for g, h in found.items() if cls_of[g] == k]
        if sel:
            out[f"recall.{c}"] = _ratio(sum(sel), len(sel))
    for (lo, hi), key, unit in ([(b, 2, "m") for b in ALTITUDE_BANDS_M]
                                + [(b, 3, "px") for b in SIZE_BANDS_PX]):
        sel = [h for inf, h in rows if lo <= inf[key] < hi]
        if sel:
            name = "alt" if unit == "m" else "size"
            out[f"recall.{name}_{_band(lo, hi, unit)}"] = _ratio(sum(sel), len(sel))
    out.update(_delay(rows))
    return out


def _delay(rows) -> dict:
    first_seen: dict = {}
    first_hit: dict = {}
    for (frame, oid, *_), hit in sorted(rows, key=lambda r: r[0][0]):
        if oid < 0:
            continue
        first_seen.setdefault(oid, frame)
        if hit:
            first_hit.setdefault(oid, frame)
    if not first_seen:
        return {}
    delays = [first_hit[o] - first_seen[o] for o in first_hit]
    return {"detection_delay_frames": float(np.mean(delays)) if delays else math.nan,
            "objects_missed": 1.0 - len(first_hit) / len(first_seen)}


def _ratio(a, b) -> float:
    return float(a) / float(b) if b else math.nan


def _precision_without_truth(recs, thr) -> float:
    n = sum(int((r.detections.scores >= thr).sum()) for r in recs)
    return 0.0 if n else math.nan


def classification_kpis(records, classes, *, score_threshold: float, min_visible: float,
                        where: str) -> dict:
    """Multi-label presence accuracy, precision and recall per class."""
    recs = [r for r in records if r.prediction is not None]
    if not recs:
        return {}
    truth = np.zeros((len(recs), len(classes)), bool)
    pred = np.zeros_like(truth)
    for i, r in enumerate(recs):
        o = r.truth
        if o is not None and len(o):
            truth[i, np.unique(o.cls[o.visible >= min_visible])] = True
        pred[i] = _labels(r.prediction, classes, score_threshold, where)
    out = {"accuracy": float((truth == pred).all(axis=1).mean())}
    for k, c in enumerate(classes):
        tp = float((truth[:, k] & pred[:, k]).sum())
        if pred[:, k].any():
            out[f"precision.{c}"] = tp / pred[:, k].sum()
        if truth[:, k].any():
            out[f"recall.{c}"] = tp / truth[:, k].sum()
    return out


def _labels(p, classes, thr, where) -> np.ndarray:
    if isinstance(p, str):
        p = [p]
    if isinstance(p, (list, tuple)) and all(isinstance(x, str) for x in p):
        bad = [x for x in p if x not in classes]
        if bad:
            raise ConfigError(f"{where}: predicted label {bad[0]!r} is not a class; allowed: "
                              f"{', '.join(classes)}")
        return np.array([c in p for c in classes])
    a = np.asarray(p, dtype=float).reshape(-1)
    if a.size != len(classes):
        raise ConfigError(f"{where}: a classification prediction has {a.size} scores; expected "
                          f"{len(classes)} (one per class: {', '.join(classes)}) or class names")
    return a >= thr
