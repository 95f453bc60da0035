"""Object annotations on disk: COCO JSON written with our renders, and a team's
own labels read back (COCO, YOLO, VisDrone-DET).

- ``coco_dataset(entries, classes)``: a COCO detection dataset (``images``,
  ``annotations`` with ``bbox = [x, y, w, h]`` in pixels, ``area``,
  ``category_id`` = class index + 1, ``iscrowd = 0``; extra fields per
  annotation: ``object_id``, ``visible``, ``distance_m``, ``gsd_m``; per image,
  ``blur_px`` when known).
- ``load_annotations(labelset, sizes, classes=None)``: the truth ``Objects`` of
  each image of a ``labelsets.LabelSet`` (which finds the layout: flat, images/ +
  labels/, an Ultralytics data.yaml, VisDrone-DET), read by ``labels_coco`` or
  ``labels_txt``. Objects keep the labels' own class names; a task matches them
  to its classes by name (``classnames``).

Every problem is a ``ConfigError`` naming the file and the entry: malformed
JSON, missing keys or values of the wrong type, boxes outside the image, unknown
categories or class ids, image sizes that differ from the image files, labels of
images that are not there.
"""

from __future__ import annotations

import math
import os

from ..errors import ConfigError
from ..world.truth import CLASSES
from .labels_coco import read_coco
from .labels_txt import read_visdrone, read_yolo


def coco_dataset(entries, classes=CLASSES, blur=None) -> dict:
    """entries: (file name, width, height, Objects) per image; ``blur``: the
    frames' blur length in pixels (None: not written)."""
    images: list[dict] = []
    anns: list[dict] = []
    for i, (name, w, h, objs) in enumerate(entries):
        images.append({"id": i + 1, "file_name": name, "width": int(w), "height": int(h)})
        if blur is not None:
            images[-1]["blur_px"] = round(float(blur[i]), 4)
        for j in range(len(objs)):
            x0, y0, x1, y1 = (float(v) for v in objs.boxes[j])
            anns.append({"id": len(anns) + 1, "image_id": i + 1,
                         "category_id": int(objs.cls[j]) + 1,
                         "bbox": [round(x0, 3), round(y0, 3), round(x1 - x0, 3), round(y1 - y0, 3)],
                         "area": round((x1 - x0) * (y1 - y0), 3), "iscrowd": 0,
                         "object_id": int(objs.ids[j]), "visible": round(float(objs.visible[j]), 4),
                         "distance_m": _num(objs.distance_m[j]), "gsd_m": _num(objs.gsd_m[j])})
    return {"info": {"description": "pytest-flockai renders with per-object ground truth"},
            "images": images, "annotations": anns,
            "categories": [{"id": k + 1, "name": c} for k, c in enumerate(classes)]}


def _num(v):
    v = float(v)
    return round(v, 4) if math.isfinite(v) else None


def load_annotations(ls, sizes, *, classes=None, where: str = "annotations"):
    """Objects per image of the LabelSet ``ls``, with ``sizes`` [(width, height)] of
    its images; returns (list of Objects, class names). ``classes`` names YOLO class
    ids when the set does not (classes.txt, data.yaml)."""
    if classes is not None and ls.fmt in ("coco", "visdrone"):
        raise ConfigError(f"{where}: classes = {list(classes)!r} names YOLO class ids; "
                          f"{ls.fmt} labels name their own categories (a task matches them "
                          f"by name)")
    if ls.fmt == "coco":
        return read_coco(ls.coco_file, ls.images, sizes)
    if ls.fmt == "visdrone":
        return read_visdrone(ls.label_files, sizes)
    if ls.fmt == "yolo":
        names = tuple(str(c) for c in classes) if classes is not None else ls.names
        if names is None:
            raise ConfigError(f"{where}: YOLO labels in {ls.label_dir!r} need class names: a "
                              f"classes.txt, a data.yaml with names:, or classes=[...]")
        return [read_yolo(lf, size, names) for lf, size in zip(ls.label_files, sizes)], names
    raise ConfigError(f"{where}: folder {ls.root!r} has no annotations.json / instances*.json "
                      f"(COCO), no <image>.txt or labels/ (YOLO) and no annotations/ (VisDrone)")


def orphan_labels(folder, files) -> list:
    """Label files (.txt) in ``folder`` whose image is not in ``files``."""
    if folder is None or not os.path.isdir(folder):
        return []
    stems = {os.path.splitext(os.path.basename(f))[0] for f in files}
    return sorted(f for f in os.listdir(folder) if f.endswith(".txt") and f != "classes.txt"
                  and os.path.splitext(f)[0] not in stems)
