"""A COCO detection file read as per-image truth ``Objects``, every value checked.

``read_coco(path, images, sizes)``: ``images`` are the image files of the set,
``sizes`` their (width, height). Each image entry is matched to an image file by
base name; each annotation's ``bbox`` ``[x, y, w, h]`` must lie in its image (up
to ``EDGE_TOLERANCE_PX``). Optional fields are checked when present: ``width`` /
``height`` (ints equal to the file's), ``iscrowd`` (0 or 1: 1 is an ignore region),
``visible`` (a fraction; our own exports write it). Ids must be ints or strings.
Every image of the folder needs an ``images`` entry (one with no annotations is an
image with no objects) and no two entries may name the same file: anything else is a
``ConfigError`` naming the file and the entry (an image would be scored as empty, or
one entry's boxes lost).
Classes are the category names, in category id order.
"""

from __future__ import annotations

import json
import math
import os
from numbers import Integral, Real

import numpy as np

from ..errors import ConfigError
from ..world.truth import Objects

#: pixels a box may reach past the image edge (rounding in labelling tools)
EDGE_TOLERANCE_PX = 1.0


def read_coco(path, images, sizes):
    """(list of Objects per image, class names) of the COCO file ``path``."""
    doc = _load(path)
    w0 = f"annotations {path!r}"
    names, cat_slot = _categories(doc["categories"], w0)
    by_name = {os.path.basename(f): (i, size) for i, (f, size) in enumerate(zip(images, sizes))}
    img_slot = _images(doc["images"], by_name, w0)
    covered = {slot for slot, _, _ in img_slot.values()}
    missing = [os.path.basename(f) for i, f in enumerate(images) if i not in covered]
    if missing:
        raise ConfigError(f"{w0}: image {missing[0]!r} of the folder has no entry in 'images'"
                          f"{f' (nor {len(missing) - 1} other image(s))' if len(missing) > 1 else ''}"
                          f"; add an entry (with no annotations: an image with no objects) or "
                          f"move the image out of the folder")
    rows: list = [[] for _ in images]
    seen = set()
    for i, a in enumerate(doc["annotations"]):
        where = f"{w0}: annotations[{i}]"
        if not isinstance(a, dict) or not {"image_id", "category_id", "bbox"} <= set(a):
            raise ConfigError(f"{where} = {a!r} needs 'image_id', 'category_id' and 'bbox'")
        aid = _id(a.get("id", -1 - i), "id", where)
        if aid in seen:
            raise ConfigError(f"{where}: id = {aid!r} is used by another annotation")
        seen.add(aid)
        iid, cid = _id(a["image_id"], "image_id", where), _id(a["category_id"], "category_id", where)
        if iid not in img_slot:
            raise ConfigError(f"{where}: image_id = {iid!r} is not in 'images'")
        if cid not in cat_slot:
            raise ConfigError(f"{where}: category_id = {cid!r} is not in 'categories' "
                              f"(ids {sorted(cat_slot, key=str)})")
        slot, w, h = img_slot[iid]
        x0, y0, x1, y1 = xywh(a["bbox"], where)
        inside(x0, y0, x1, y1, w, h, where)
        crowd = _flag(a.get("iscrowd", 0), "iscrowd", where)
        vis = 0.0 if crowd else _fraction(a.get("visible", 1.0), "visible", where)
        rows[slot].append((aid if isinstance(aid, int) else -1, cat_slot[cid], x0, y0, x1, y1, vis))
    return [objects_of(r, names) for r in rows], names


def _load(path) -> dict:
    try:
        with open(path, encoding="utf-8") as f:
            doc = json.load(f)
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ConfigError(f"annotations {path!r}: not a readable JSON file ({exc})") from None
    for key in ("images", "annotations", "categories"):
        if not isinstance(doc, dict) or not isinstance(doc.get(key), list):
            raise ConfigError(f"annotations {path!r}: missing list {key!r}; a COCO file has "
                              f"'images', 'annotations' and 'categories'")
    return doc


def _categories(cats, w0):
    by_id: dict = {}
    for i, c in enumerate(cats):
        where = f"{w0}: categories[{i}]"
        if not isinstance(c, dict) or "id" not in c or "name" not in c:
            raise ConfigError(f"{where} = {c!r} needs 'id' and 'name'")
        cid = _id(c["id"], "id", where)
        if cid in by_id:
            raise ConfigError(f"{where}: id = {cid!r} is used by another category")
        if not isinstance(c["name"], str) or not c["name"].strip():
            raise ConfigError(f"{where}: name = {c['name']!r} is not allowed; expected a "
                              f"non-empty string")
        by_id[cid] = c["name"].strip()
    order = sorted(by_id, key=lambda k: (isinstance(k, str), k))
    return tuple(by_id[k] for k in order), {k: j for j, k in enumerate(order)}


def _images(entries, by_name, w0) -> dict:
    img_slot: dict = {}
    names_seen: dict = {}
    for i, im in enumerate(entries):
        where = f"{w0}: images[{i}]"
        if not isinstance(im, dict) or not {"id", "file_name"} <= set(im):
            raise ConfigError(f"{where} = {im!r} needs 'id' and 'file_name'")
        iid = _id(im["id"], "id", where)
        if iid in img_slot:
            raise ConfigError(f"{where}: id = {iid!r} is used by another image")
        if not isinstance(im["file_name"], str):
            raise ConfigError(f"{where}: file_name = {im['file_name']!r} is not a string")
        base = os.path.basename(im["file_name"])
        if base not in by_name:
            raise ConfigError(f"{where}: file_name = {im['file_name']!r} is not an image of the folder")
        slot, (w, h) = by_name[base]
        if base in names_seen:
            raise ConfigError(f"{where}: file_name = {im['file_name']!r} is also the file of "
                              f"images[{names_seen[base]}]; one entry per image file")
        names_seen[base] = i
        sz = [_count(im[k], k, where) for k in ("width", "height") if k in im]
        if len(sz) == 2 and tuple(sz) != (w, h):
            raise ConfigError(f"{where}: size {sz[0]}x{sz[1]} differs from the image file's {w}x{h}")
        img_slot[iid] = (slot, w, h)
    return img_slot


def _id(v, field, where):
    if isinstance(v, bool) or not isinstance(v, (Integral, str)):
        raise ConfigError(f"{where}: {field} = {v!r} is not allowed; expected an int (or a string) id")
    return int(v) if isinstance(v, Integral) else v


def _count(v, field, where) -> int:
    if isinstance(v, bool) or not isinstance(v, Integral) or v <= 0:
        raise ConfigError(f"{where}: {field} = {v!r} is not allowed; expected an int > 0 (pixels)")
    return int(v)


def _flag(v, field, where) -> bool:
    if not isinstance(v, (Integral, bool)) or v not in (0, 1):
        raise ConfigError(f"{where}: {field} = {v!r} is not allowed; expected 0 or 1")
    return bool(v)


def _fraction(v, field, where) -> float:
    if isinstance(v, bool) or not isinstance(v, Real) or not 0.0 <= float(v) <= 1.0:
        raise ConfigError(f"{where}: {field} = {v!r} is not allowed; expected a fraction in [0, 1]")
    return float(v)


def xywh(b, where):
    """(x0, y0, x1, y1) of a COCO ``[x, y, width, height]`` box."""
    if not isinstance(b, (list, tuple)) or len(b) != 4 or not all(
            isinstance(v, Real) and not isinstance(v, bool) for v in b):
        raise ConfigError(f"{where}: bbox = {b!r} is not [x, y, width, height]")
    x, y, w, h = (float(v) for v in b)
    if not all(math.isfinite(v) for v in (x, y, w, h)) or w <= 0 or h <= 0:
        raise ConfigError(f"{where}: bbox = {b!r} is not allowed; expected finite "
                          f"[x, y, width, height] with width and height > 0")
    return x, y, x + w, y + h


def inside(x0, y0, x1, y1, w, h, where):
    """ConfigError for a box outside the w x h image (beyond the tolerance)."""
    tol = EDGE_TOLERANCE_PX
    if x0 < -tol or y0 < -tol or x1 > w + tol or y1 > h + tol:
        raise ConfigError(f"{where}: box ({x0:g}, {y0:g}, {x1:g}, {y1:g}) lies outside the "
                          f"{w}x{h} image")


def objects_of(rows, names) -> Objects:
    """Objects from rows (id, class, x0, y0, x1, y1, visible), boxes clipped to the image."""
    a = np.array(rows, dtype=float).reshape(-1, 7)
    n = len(a)
    box = np.column_stack([np.clip(a[:, 2], 0, None), np.clip(a[:, 3], 0, None), a[:, 4], a[:, 5]])
    return Objects(ids=a[:, 0].astype(int), cls=a[:, 1].astype(int), boxes=box, visible=a[:, 6],
                   distance_m=np.full(n, np.nan), gsd_m=np.full(n, np.nan), classes=tuple(names))
