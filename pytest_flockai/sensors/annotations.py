"""Object annotations on disk: COCO JSON written with our renders, and COCO or
YOLO labels read from a team's own recorded frames.

- ``coco_dataset(entries, classes)``: a COCO detection dataset (``images``,
  ``annotations`` with ``bbox = [x, y, w, h]`` in pixels, ``area``,
  ``category_id`` = class index + 1, ``iscrowd = 0``; extra fields per
  annotation: ``object_id``, ``visible``, ``distance_m``, ``gsd_m``).
- ``load_annotations(folder, files, sizes, fmt="auto", classes=None)``: the
  truth ``Objects`` of each image of a folder, from ``annotations.json`` /
  ``instances*.json`` (COCO) or one ``<image stem>.txt`` per image (YOLO:
  ``class cx cy w h`` normalised to [0, 1]; class names from ``classes.txt``,
  ``data.yaml``'s ``names:`` or ``classes=``).

Every problem is a ``ConfigError`` naming the file and the entry: malformed
JSON, missing keys, boxes outside the image, unknown categories or class ids,
image sizes that differ from the image files, labels of images that are not
there.
"""

from __future__ import annotations

import json
import math
import os

import numpy as np

from ..errors import ConfigError
from ..world.truth import CLASSES, Objects

#: pixels a box may reach past the image edge (rounding in labelling tools)
EDGE_TOLERANCE_PX = 1.0


def coco_dataset(entries, classes=CLASSES) -> dict:
    """entries: (file name, width, height, Objects) per image."""
    images, anns = [], []
    for i, (name, w, h, objs) in enumerate(entries):
        images.append({"id": i + 1, "file_name": name, "width": int(w), "height": int(h)})
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


def load_annotations(folder, files, sizes, *, fmt: str = "auto", classes=None):
    """Objects per image of ``files`` (paths in ``folder``), with ``sizes``
    [(width, height)]; returns (list of Objects, class names)."""
    folder = os.fspath(folder)
    coco = _coco_file(folder)
    if fmt == "auto":
        fmt = "coco" if coco else ("yolo" if any(_yolo_label(f) for f in files) else None)
        if fmt is None:
            raise ConfigError(f"annotations: folder {folder!r} has no annotations.json / "
                              f"instances*.json (COCO) and no <image>.txt labels (YOLO)")
    if fmt == "coco":
        if not coco:
            raise ConfigError(f"annotations: folder {folder!r} has no annotations.json or "
                              f"instances*.json")
        return _read_coco(coco, files, sizes, classes)
    if fmt == "yolo":
        names = _yolo_names(folder, classes)
        return [_read_yolo(f, size, names) for f, size in zip(files, sizes)], names
    raise ConfigError(f"annotations: fmt = {fmt!r} is not allowed; allowed: 'auto', 'coco', 'yolo'")


def _coco_file(folder):
    for name in ["annotations.json"] + sorted(f for f in os.listdir(folder)
                                              if f.startswith("instances") and f.endswith(".json")):
        p = os.path.join(folder, name)
        if os.path.isfile(p):
            return p
    return None


def _read_coco(path, files, sizes, classes):
    try:
        with open(path) as f:
            doc = json.load(f)
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ConfigError(f"annotations {path!r}: not a readable JSON file ({exc})") from None
    for key in ("images", "annotations", "categories"):
        if not isinstance(doc, dict) or not isinstance(doc.get(key), list):
            raise ConfigError(f"annotations {path!r}: missing list {key!r}; a COCO file has "
                              f"'images', 'annotations' and 'categories'")
    cats = {}
    for i, c in enumerate(doc["categories"]):
        if not isinstance(c, dict) or "id" not in c or "name" not in c:
            raise ConfigError(f"annotations {path!r}: categories[{i}] = {c!r} needs 'id' and 'name'")
        cats[c["id"]] = str(c["name"])
    names = tuple(classes) if classes is not None else tuple(cats[k] for k in sorted(cats))
    index = {cid: names.index(n) for cid, n in cats.items() if n in names}
    by_name = {os.path.basename(f): (i, size) for i, (f, size) in enumerate(zip(files, sizes))}
    img_slot = {}
    for i, im in enumerate(doc["images"]):
        where = f"annotations {path!r}: images[{i}]"
        if not isinstance(im, dict) or not {"id", "file_name"} <= set(im):
            raise ConfigError(f"{where} = {im!r} needs 'id' and 'file_name'")
        base = os.path.basename(str(im["file_name"]))
        if base not in by_name:
            raise ConfigError(f"{where}: file_name = {im['file_name']!r} is not an image of the folder")
        slot, (w, h) = by_name[base]
        if "width" in im and "height" in im and (int(im["width"]), int(im["height"])) != (w, h):
            raise ConfigError(f"{where}: size {im['width']}x{im['height']} differs from the image "
                              f"file's {w}x{h}")
        img_slot[im["id"]] = (slot, w, h)
    rows = [[] for _ in files]
    for i, a in enumerate(doc["annotations"]):
        where = f"annotations {path!r}: annotations[{i}]"
        if not isinstance(a, dict) or not {"image_id", "category_id", "bbox"} <= set(a):
            raise ConfigError(f"{where} = {a!r} needs 'image_id', 'category_id' and 'bbox'")
        if a["image_id"] not in img_slot:
            raise ConfigError(f"{where}: image_id = {a['image_id']!r} is not in 'images'")
        if a["category_id"] not in cats:
            raise ConfigError(f"{where}: category_id = {a['category_id']!r} is not in 'categories' "
                              f"(ids {sorted(cats)})")
        if a["category_id"] not in index:
            continue                                  # a class the task does not score
        slot, w, h = img_slot[a["image_id"]]
        x0, y0, x1, y1 = _xywh(a["bbox"], where)
        _inside(x0, y0, x1, y1, w, h, where)
        vis = 0.0 if a.get("iscrowd") else float(a.get("visible", 1.0))
        rows[slot].append((a.get("id", -1), index[a["category_id"]], x0, y0, x1, y1, vis))
    return [_objects(r, names) for r in rows], names


def _xywh(b, where):
    try:
        x, y, w, h = (float(v) for v in b)
    except (TypeError, ValueError):
        raise ConfigError(f"{where}: bbox = {b!r} is not [x, y, width, height]") from None
    if not all(math.isfinite(v) for v in (x, y, w, h)) or w <= 0 or h <= 0:
        raise ConfigError(f"{where}: bbox = {b!r} is not allowed; expected finite "
                          f"[x, y, width, height] with width and height > 0")
    return x, y, x + w, y + h


def _inside(x0, y0, x1, y1, w, h, where):
    tol = EDGE_TOLERANCE_PX
    if x0 < -tol or y0 < -tol or x1 > w + tol or y1 > h + tol:
        raise ConfigError(f"{where}: box ({x0:g}, {y0:g}, {x1:g}, {y1:g}) lies outside the "
                          f"{w}x{h} image")


def _objects(rows, names) -> Objects:
    a = np.array(rows, dtype=float).reshape(-1, 7)
    n = len(a)
    box = np.column_stack([np.clip(a[:, 2], 0, None), np.clip(a[:, 3], 0, None), a[:, 4], a[:, 5]])
    return Objects(ids=a[:, 0].astype(int), cls=a[:, 1].astype(int), boxes=box, visible=a[:, 6],
                   distance_m=np.full(n, np.nan), gsd_m=np.full(n, np.nan), classes=tuple(names))


def _yolo_label(image_path):
    p = os.path.splitext(image_path)[0] + ".txt"
    return p if os.path.isfile(p) else None


def _yolo_names(folder, classes):
    if classes is not None:
        return tuple(classes)
    txt = os.path.join(folder, "classes.txt")
    if os.path.isfile(txt):
        with open(txt) as f:
            return tuple(line.strip() for line in f if line.strip())
    yml = os.path.join(folder, "data.yaml")
    if os.path.isfile(yml):
        return _yaml_names(yml)
    raise ConfigError(f"annotations: YOLO labels in {folder!r} need class names: a classes.txt, "
                      f"a data.yaml with names:, or classes=[...]")


def _yaml_names(path):
    """``names:`` of a YOLO data.yaml: an inline list or a block of ``- name`` / ``i: name``."""
    names, inside = [], False
    with open(path) as f:
        for line in f:
            s = line.strip()
            if s.startswith("names:"):
                rest = s[len("names:"):].strip()
                if rest.startswith("["):
                    return tuple(x.strip().strip("'\"") for x in rest.strip("[]").split(",") if x.strip())
                inside = True
            elif inside and (s.startswith("-") or ":" in s) and line[:1].isspace():
                names.append(s.lstrip("-").split(":", 1)[-1].strip().strip("'\""))
            elif inside and s:
                break
    if not names:
        raise ConfigError(f"annotations: {path!r} has no 'names:' list")
    return tuple(names)


def _read_yolo(image_path, size, names) -> Objects:
    label = _yolo_label(image_path)
    w, h = size
    rows = []
    if label is not None:
        with open(label) as f:
            for ln, line in enumerate(f, 1):
                if not line.strip():
                    continue
                where = f"annotations {label!r}: line {ln}"
                parts = line.split()
                try:
                    c = int(parts[0])
                    cx, cy, bw, bh = (float(v) for v in parts[1:5])
                except (ValueError, IndexError):
                    raise ConfigError(f"{where} = {line.strip()!r} is not 'class cx cy w h'") from None
                if not 0 <= c < len(names):
                    raise ConfigError(f"{where}: class {c} is unknown; classes 0..{len(names) - 1}: "
                                      f"{', '.join(names)}")
                if not (0 < bw <= 1 and 0 < bh <= 1 and all(math.isfinite(v) for v in (cx, cy))):
                    raise ConfigError(f"{where}: box {cx:g} {cy:g} {bw:g} {bh:g} is not normalised "
                                      f"to (0, 1]")
                x0, y0, x1, y1 = (cx - bw / 2) * w, (cy - bh / 2) * h, (cx + bw / 2) * w, (cy + bh / 2) * h
                _inside(x0, y0, x1, y1, w, h, where)
                rows.append((-1, c, x0, y0, x1, y1, 1.0))
    return _objects(rows, names)


def orphan_labels(folder, files) -> list:
    """YOLO label files whose image is not in ``files``."""
    stems = {os.path.splitext(os.path.basename(f))[0] for f in files}
    return sorted(f for f in os.listdir(folder) if f.endswith(".txt") and f != "classes.txt"
                  and os.path.splitext(f)[0] not in stems)
