"""The worst frames of a detection task, drawn: what the model got wrong, to look at.

``worst_frames(records, task, n=6)`` matches each frame's detections to its truth
with COCOeval (``evaluation.run_cocoeval``, IoU 0.5, detections at the task's
``score_threshold``), ranks the frames by their mistakes (false positives plus
misses, then misses first) and draws the worst ``n`` with OpenCV at twice their
size: true positives green, false positives red, misses orange, ignore regions
grey (``COLOURS``). Each entry carries the PNG (base64) and what the dashboard
prints under it: the frame's time, file, altitude, blur length, and per object its
class, visible fraction and score. Replayed frames are read from their files;
rendered ones from the JPEG the scorer kept (``FrameRecord.image``).
"""

from __future__ import annotations

import base64
import math
import os

import cv2
import numpy as np

from .evaluation import MAX_DETS, run_cocoeval
from .jpeg import decode_jpeg

#: box colours (RGB) by what the box is
COLOURS = {"tp": (40, 200, 60), "fp": (230, 40, 40), "miss": (255, 150, 0), "ignore": (150, 150, 150)}
#: the drawing's scale: boxes of 3-20 px people stay visible under a 1 px line
SCALE = 3


def frame_boxes(records, classes, *, min_visible: float, score_threshold: float) -> dict:
    """{frame index: [(kind, class, x0, y0, x1, y1, score or NaN, visible or NaN)]}."""
    recs = [r for r in records if r.detections is not None]
    ev, gt, _, _ = run_cocoeval(recs, classes, min_visible)
    out: dict = {r.index: [] for r in recs}
    if ev is None:
        return out
    gts, dts = ev.cocoGt.anns, ev.cocoDt.anns
    vis = {(r.index, j): float(r.truth.visible[j]) for r in recs for j in range(len(r.truth))}
    order = {a["id"]: k for k, a in enumerate(gt["annotations"])}
    first = _first_ann_per_image(gt)
    for e in ev.evalImgs:
        if e is None or e["maxDet"] != MAX_DETS[-1]:
            continue
        idx = e["image_id"] - 1
        for j, did in enumerate(e["dtIds"]):
            d = dts[did]
            if d["score"] < score_threshold or e["dtIgnore"][0, j]:
                continue
            kind = "tp" if e["dtMatches"][0, j] > 0 else "fp"
            out[idx].append((kind, d["category_id"] - 1, *_xyxy(d["bbox"]), d["score"], math.nan))
        for g, gid in enumerate(e["gtIds"]):
            hit = int(e["gtMatches"][0, g])
            a = gts[gid]
            v = vis.get((idx, order[gid] - first[idx]), math.nan)
            if e["gtIgnore"][g]:
                kind = "ignore"
            elif hit == 0 or dts[hit]["score"] < score_threshold:
                kind = "miss"
            else:
                continue                        # found: drawn as its true positive
            out[idx].append((kind, a["category_id"] - 1, *_xyxy(a["bbox"]), math.nan, v))
    return out


def _first_ann_per_image(gt) -> dict:
    first: dict = {}
    for k, a in enumerate(gt["annotations"]):
        first.setdefault(a["image_id"] - 1, k)
    return first


def _xyxy(b):
    return float(b[0]), float(b[1]), float(b[0] + b[2]), float(b[1] + b[3])


def worst_frames(records, task, n: int = 6) -> list[dict]:
    """The ``n`` frames with the most mistakes, drawn (see the module docstring)."""
    boxes = frame_boxes(records, task.classes, min_visible=task.min_visible,
                        score_threshold=task.score_threshold)
    by = {r.index: r for r in records}

    def cost(i):
        b = boxes[i]
        return (sum(k in ("fp", "miss") for k, *_ in b), sum(k == "miss" for k, *_ in b))
    ranked = sorted((i for i in boxes if cost(i)[0] > 0), key=lambda i: (-cost(i)[0], -cost(i)[1], i))
    out = []
    for i in ranked[:n]:
        img = _image(by[i])
        if img is None:
            continue
        out.append(_entry(by[i], boxes[i], img, task.classes))
    return out


def _image(rec):
    if rec.file:
        img = cv2.imread(rec.file, cv2.IMREAD_COLOR)
        return None if img is None else cv2.cvtColor(img, cv2.COLOR_BGR2RGB)
    return decode_jpeg(rec.image, grey=False) if rec.image else None


def draw(img, boxes) -> np.ndarray:
    """``img`` (RGB) at ``SCALE`` with the boxes drawn (2 px lines inside each box),
    ignore regions and misses first."""
    out = cv2.resize(img, None, fx=SCALE, fy=SCALE, interpolation=cv2.INTER_NEAREST)
    for kind in ("ignore", "miss", "fp", "tp"):
        for k, _, x0, y0, x1, y1, *_ in boxes:
            if k != kind:
                continue
            a, b = (round(x0 * SCALE), round(y0 * SCALE)), (round(x1 * SCALE) - 1, round(y1 * SCALE) - 1)
            for inset in (0, 1):                 # 2 px inside the box: never on a neighbour's
                cv2.rectangle(out, (a[0] + inset, a[1] + inset), (b[0] - inset, b[1] - inset),
                              COLOURS[k], 1)
    return out


def _entry(rec, boxes, img, classes) -> dict:
    ok, png = cv2.imencode(".png", cv2.cvtColor(draw(img, boxes), cv2.COLOR_RGB2BGR))
    objs = [{"kind": k, "class": classes[c] if 0 <= c < len(classes) else str(c),
             "box": [round(v, 1) for v in (x0, y0, x1, y1)],
             **({"score": round(s, 3)} if s == s else {}), **({"visible": round(v, 2)} if v == v else {})}
            for k, c, x0, y0, x1, y1, s, v in boxes]
    return {"index": rec.index, "file": os.path.basename(rec.file) if rec.file else None,
            "t": rec.t, "altitude_m": rec.altitude_m, "blur_px": rec.blur_px,
            "width": rec.width, "height": rec.height, "scale": SCALE, "objects": objs,
            "png": base64.b64encode(png.tobytes()).decode() if ok else ""}
