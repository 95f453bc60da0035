"""What a detector got right and wrong, from COCOeval's own arrays (never re-implemented).

``analyse(records, classes)`` runs pycocotools' ``COCOeval`` on the frames a task
scored (``evaluation.run_cocoeval``: the same inputs as the KPIs) and reads:

- ``pr_curves[class]``: precision at each of COCO's 101 recall thresholds
  (``recall_thresholds``), IoU 0.5: ``eval["precision"][0, :, k, 0, -1]``
  (-1 where the recall is never reached); ``scores[class]`` the detection score
  at each (``eval["scores"]``);
- ``ap[class]``: ``ap50`` and ``ap50_95``, the means of those arrays as the KPIs
  ``map50.<class>`` are; ``stats``: ``COCOeval.stats`` after ``summarize()``
  (entries for the small/medium/large areas are -1: aerial frames are scored on
  one area range, see ``evaluation``);
- ``f1_best[class]`` and ``f1_best["all"]``: the score threshold with the best
  F1 on the interpolated PR curve (from ``precision`` and ``scores``; "all" from a
  class-agnostic run, ``useCats = 0``);
- ``confusion``: truth class (rows, then "background": detections on nothing) by
  predicted class (columns, then "background": misses), counted from the
  class-agnostic run's matches (``evalImgs``' ``dtMatches``/``gtMatches`` at IoU
  0.5) for detections at the task's ``score_threshold``.

``write_coco_pair(records, classes, folder, name)`` writes the ground truth and the
predictions as COCO files (``<name>.truth.json``, ``<name>.results.json``) that
pycocotools (``COCO``, ``loadRes``) and FiftyOne load.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
from typing import IO

import numpy as np

from .._io import atomic_write
from .evaluation import MAX_DETS, _coco_inputs, run_cocoeval


def analyse(records, classes, *, min_visible: float, score_threshold: float) -> dict:
    """The analyses of the module docstring ({} when no frame has truth)."""
    recs = [r for r in records if r.detections is not None]
    ev, gt, _, _ = run_cocoeval(recs, classes, min_visible)
    if ev is None:
        return {}
    with contextlib.redirect_stdout(io.StringIO()):
        ev.summarize()
    prec, sc = ev.eval["precision"], ev.eval["scores"]
    out = {"recall_thresholds": ev.params.recThrs.tolist(),
           "iou_thresholds": ev.params.iouThrs.tolist(), "stats": ev.stats.tolist(),
           "pr_curves": {}, "scores": {}, "ap": {}, "f1_best": {}}
    for k, c in enumerate(classes):
        p50 = prec[0, :, k, 0, -1]
        if not (p50 > -1).any():
            continue                        # no truth of this class
        pall = prec[:, :, k, 0, -1]
        out["pr_curves"][c] = p50.tolist()
        out["scores"][c] = sc[0, :, k, 0, -1].tolist()
        out["ap"][c] = {"ap50": float(p50[p50 > -1].mean()), "ap50_95": float(pall[pall > -1].mean())}
        out["f1_best"][c] = _f1_best(p50, sc[0, :, k, 0, -1], ev.params.recThrs)
    agn = run_cocoeval(recs, classes, min_visible, use_cats=False)[0]
    out["f1_best"]["all"] = _f1_best(agn.eval["precision"][0, :, 0, 0, -1],
                                     agn.eval["scores"][0, :, 0, 0, -1], agn.params.recThrs)
    out["confusion"] = _confusion(agn, gt, classes, score_threshold)
    return out


def _f1_best(p, s, r) -> dict:
    ok = p > 0
    if not ok.any():
        return {"threshold": None, "f1": 0.0, "precision": 0.0, "recall": 0.0}
    f1 = np.where(ok, 2 * p * r / np.where(ok, p + r, 1.0), -1.0)
    i = int(np.argmax(f1))
    return {"threshold": float(s[i]), "f1": float(f1[i]), "precision": float(p[i]),
            "recall": float(r[i])}


def _confusion(ev, gt, classes, thr) -> dict:
    n = len(classes)
    m = np.zeros((n + 1, n + 1), dtype=int)
    gt_cls = {a["id"]: a["category_id"] - 1 for a in gt["annotations"]}
    dts = ev.cocoDt.anns
    for e in ev.evalImgs:
        if e is None or e["maxDet"] != MAX_DETS[-1]:
            continue
        for j, did in enumerate(e["dtIds"]):
            d = dts[did]
            if d["score"] < thr or e["dtIgnore"][0, j]:
                continue
            g = int(e["dtMatches"][0, j])
            m[gt_cls[g] if g > 0 else n, d["category_id"] - 1] += 1
        for g, gid in enumerate(e["gtIds"]):
            hit = int(e["gtMatches"][0, g])
            if not e["gtIgnore"][g] and (hit == 0 or dts[hit]["score"] < thr):
                m[gt_cls[gid], n] += 1
    return {"labels": list(classes) + ["background"], "matrix": m.tolist(),
            "score_threshold": float(thr)}


def coco_pair(records, classes, *, min_visible: float):
    """(ground truth dict, results list) of the frames a task scored, COCO format."""
    recs = [r for r in records if r.detections is not None]
    gt, dts, _ = _coco_inputs(recs, classes, min_visible)
    return gt, dts


def write_coco_pair(records, classes, folder, name: str, *, min_visible: float) -> dict:
    """Write ``<name>.truth.json`` and ``<name>.results.json`` in ``folder``; their paths."""
    gt, dts = coco_pair(records, classes, min_visible=min_visible)
    os.makedirs(folder, exist_ok=True)
    paths = {"truth": os.path.join(folder, f"{name}.truth.json"),
             "results": os.path.join(folder, f"{name}.results.json")}
    for key, doc in (("truth", gt), ("results", dts)):
        text = json.dumps(doc)

        def write(fh: IO[str], t: str = text) -> None:
            fh.write(t)
        atomic_write(paths[key], write)
    return paths
