"""Labelled image folders for the dataset-mode tests, in every layout the readers take.

Each image (160 x 128, grey) holds two red people and one blue vehicle filling
16 x 16 cells of a grid; the bottom-right pixel's red value is the image's index,
so a "perfect model" can look its labels up (``perfect_model``). ``make_set``
writes the labels as COCO, YOLO (flat or images/ + labels/ with a data.yaml) or
VisDrone-DET, naming the classes as such sets do (car, pedestrian...).
"""

import json

import cv2
import numpy as np

W, H, CELL = 160, 128, 16
RED, BLUE = (255, 0, 0), (0, 0, 255)


def scene(n, seed=0):
    """Per image: [(class, x, y, w, h)] with class 0 person, 1 vehicle; plus an extra
    red cell per image (VisDrone's ignored region covers it)."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        cells = rng.choice((W // CELL) * (H // CELL) - 1, size=4, replace=False)
        boxes = [(0 if k < 2 else 1, int(c % (W // CELL)) * CELL, int(c // (W // CELL)) * CELL,
                  CELL, CELL) for k, c in enumerate(cells[:3])]
        c = cells[3]
        out.append((boxes, (int(c % (W // CELL)) * CELL, int(c // (W // CELL)) * CELL)))
    return out


def _image(i, boxes, extra):
    img = np.full((H, W, 3), 90, np.uint8)
    for c, x, y, w, h in boxes:
        img[y:y + h, x:x + w] = RED if c == 0 else BLUE
    if extra is not None:
        img[extra[1]:extra[1] + CELL, extra[0]:extra[0] + CELL] = RED
    img[-1, -1, 0] = i
    return img


def _write(path, img):
    path.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(path), cv2.cvtColor(img, cv2.COLOR_RGB2BGR))


def make_set(root, layout, n=40, seed=0, *, categories=None):
    """Write ``n`` labelled images at ``root`` in ``layout`` ("coco", "yolo-flat",
    "yolo-images-labels", "visdrone"); returns (the path to give a reader, scene)."""
    sc = scene(n, seed)
    vis = layout == "visdrone"
    for i, (boxes, extra) in enumerate(sc):
        img = _image(i, boxes, extra if vis else None)
        if layout in ("coco", "yolo-flat"):
            _write(root / f"f{i:02d}.png", img)
        elif layout == "yolo-images-labels":
            _write(root / "images" / "val" / f"f{i:02d}.png", img)
        else:
            _write(root / "images" / f"f{i:02d}.png", img)
    if layout == "coco":
        _coco(root, sc, categories or [{"id": 1, "name": "car"}, {"id": 2, "name": "person"}])
        return root, sc
    if layout == "yolo-flat":
        (root / "classes.txt").write_text("person\nvehicle\n")
        _yolo(root, sc, {0: 0, 1: 1})
        return root, sc
    if layout == "yolo-images-labels":
        (root / "data.yaml").write_text("path: .\ntrain: images/train\nval: images/val\n"
                                        "names:\n  0: car\n  1: pedestrian\n")
        (root / "images" / "train").mkdir()
        _yolo(root / "labels" / "val", sc, {0: 1, 1: 0})
        return root / "data.yaml", sc
    _visdrone(root / "annotations", sc)
    return root, sc


def _coco(root, sc, cats):
    cid = {("person" if c["name"] in ("person", "pedestrian") else "vehicle"): c["id"] for c in cats}
    images = [{"id": i + 1, "file_name": f"f{i:02d}.png", "width": W, "height": H}
              for i in range(len(sc))]
    anns = [{"id": 1000 + 3 * i + k, "image_id": i + 1,
             "category_id": cid["person" if c == 0 else "vehicle"], "bbox": [x, y, w, h],
             "area": w * h, "iscrowd": 0}
            for i, (boxes, _) in enumerate(sc) for k, (c, x, y, w, h) in enumerate(boxes)]
    (root / "annotations.json").write_text(json.dumps(
        {"images": images, "annotations": anns, "categories": cats}))


def _yolo(folder, sc, ids):
    folder.mkdir(parents=True, exist_ok=True)
    for i, (boxes, _) in enumerate(sc):
        (folder / f"f{i:02d}.txt").write_text("".join(
            f"{ids[c]} {(x + w / 2) / W} {(y + h / 2) / H} {w / W} {h / H}\n"
            for c, x, y, w, h in boxes))


def _visdrone(folder, sc):
    folder.mkdir(parents=True, exist_ok=True)
    for i, (boxes, extra) in enumerate(sc):
        rows = [f"{x},{y},{w},{h},1,{1 if c == 0 else 4},0,0" for c, x, y, w, h in boxes]
        rows.append(f"{extra[0]},{extra[1]},{CELL},{CELL},0,0,0,0")      # an ignored region
        (folder / f"f{i:02d}.txt").write_text("\n".join(rows) + "\n")


def perfect_model(sc, *, extra=False, keep=lambda i, k: True):
    """fn(frame) -> (N, 6) rows: the image's labels (its index in the corner pixel);
    ``extra``: also a person where the ignored region is; ``keep``: which boxes."""
    def model(frame):
        i = int(frame[-1, -1, 0])
        boxes, cell = sc[i]
        rows = [[x, y, x + w, y + h, 0.9, c] for k, (c, x, y, w, h) in enumerate(boxes) if keep(i, k)]
        if extra:
            rows.append([cell[0], cell[1], cell[0] + CELL, cell[1] + CELL, 0.8, 0])
        return np.array(rows, dtype=float).reshape(-1, 6)
    return model
