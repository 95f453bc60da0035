"""Text labels, one file per image: YOLO and VisDrone-DET.

- YOLO: ``class cx cy w h`` per line, the box normalised to (0, 1] by the image
  size; class ids index the set's names (classes.txt, data.yaml ``names:``).
- VisDrone-DET (Zhu et al., "Detection and Tracking Meet Drones Challenge",
  TPAMI 2021; the toolkit's annotation format): ``x,y,w,h,score,category,
  truncation,occlusion`` per line in pixels. ``score`` 0 marks a box the
  benchmark ignores, category 0 is an "ignored region" and 11 "others": all three
  become ignore regions (visible 0). Occlusion 0 / 1 / 2 (none, 1-50 %, 50-100 %
  hidden) is read as the visible fraction 1.0 / 0.75 / 0.25, the middle of
  each band.
"""

from __future__ import annotations

import math

from ..errors import ConfigError
from .labels_coco import inside, objects_of
from .labelsets import read_text

#: VisDrone-DET categories, by their id in the annotation files
VISDRONE_CLASSES = ("ignored regions", "pedestrian", "people", "bicycle", "car", "van", "truck",
                    "tricycle", "awning-tricycle", "bus", "motor", "others")
#: visible fraction for VisDrone occlusion 0, 1, 2 (the middle of each band)
VISDRONE_VISIBLE = (1.0, 0.75, 0.25)


def read_yolo(label, size, names):
    """Objects of one image from its YOLO label file (None: no objects)."""
    w, h = size
    rows = []
    for ln, line in _lines(label):
        where = f"annotations {label!r}: line {ln}"
        parts = line.split()
        try:
            if len(parts) != 5:
                raise ValueError
            c = int(parts[0])
            cx, cy, bw, bh = (float(v) for v in parts[1:5])
        except ValueError:
            raise ConfigError(f"{where} = {line.strip()!r} is not 'class cx cy w h'") from None
        if not 0 <= c < len(names):
            raise ConfigError(f"{where}: class {c} is unknown; classes 0..{len(names) - 1}: "
                              f"{', '.join(names)}")
        if not (0 < bw <= 1 and 0 < bh <= 1 and all(math.isfinite(v) for v in (cx, cy))):
            raise ConfigError(f"{where}: box {cx:g} {cy:g} {bw:g} {bh:g} is not normalised "
                              f"to (0, 1]")
        x0, y0, x1, y1 = (cx - bw / 2) * w, (cy - bh / 2) * h, (cx + bw / 2) * w, (cy + bh / 2) * h
        inside(x0, y0, x1, y1, w, h, where)
        rows.append((-1, c, x0, y0, x1, y1, 1.0))
    return objects_of(rows, names)


def read_visdrone(label_files, sizes):
    """(Objects per image, VISDRONE_CLASSES) from VisDrone-DET annotation files."""
    return [_visdrone_one(lf, size) for lf, size in zip(label_files, sizes)], VISDRONE_CLASSES


def _visdrone_one(label, size):
    w, h = size
    rows = []
    for ln, line in _lines(label):
        where = f"annotations {label!r}: line {ln}"
        parts = [p for p in line.strip().rstrip(",").split(",")]
        try:
            if len(parts) < 6:
                raise ValueError
            x, y, bw, bh = (float(v) for v in parts[:4])
            score, cat = int(parts[4]), int(parts[5])
            occ = int(parts[7]) if len(parts) > 7 else 0
        except ValueError:
            raise ConfigError(f"{where} = {line.strip()!r} is not 'x,y,w,h,score,category,"
                              f"truncation,occlusion'") from None
        if not 0 <= cat < len(VISDRONE_CLASSES):
            raise ConfigError(f"{where}: category {cat} is unknown; VisDrone-DET categories "
                              f"0..11: {', '.join(VISDRONE_CLASSES)}")
        if score not in (0, 1) or occ not in (0, 1, 2):
            raise ConfigError(f"{where}: score = {score}, occlusion = {occ} is not allowed; "
                              f"expected score 0 or 1 and occlusion 0, 1 or 2")
        if not all(math.isfinite(v) for v in (x, y, bw, bh)) or bw <= 0 or bh <= 0:
            raise ConfigError(f"{where}: box {x:g},{y:g},{bw:g},{bh:g} needs a width and a "
                              f"height > 0")
        inside(x, y, x + bw, y + bh, w, h, where)
        ignore = score == 0 or cat in (0, 11)
        rows.append((-1, cat, x, y, x + bw, y + bh, 0.0 if ignore else VISDRONE_VISIBLE[occ]))
    return objects_of(rows, VISDRONE_CLASSES)


def _lines(path):
    if path is None:
        return []
    text = read_text(path, "annotations")        # UTF-8, a regular file: else ConfigError
    return [(i, line) for i, line in enumerate(text.splitlines(), 1) if line.strip()]
