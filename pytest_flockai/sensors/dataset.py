"""Export frames and their ground truth as a dataset (for training and replay).

``export_dataset(records, folder)`` takes ``(t, frame, truth)`` records (from
a flown mission: the camera's ``last_t``, ``last_frame``, ``last_truth`` at
each capture; or from ``render_views``) and writes

- ``frame_00000.png`` ... (RGB frames written with ``cv2.imwrite``; ``fmt="jpg"``
  for JPEG),
- ``truth.csv``: one row per frame: ``frame, file, t, count, pixels`` (pixels
  as a JSON list of [u, v]),
- ``truth.json``: ``{"frames": [{"frame", "file", "t", "count", "indices",
  "pixels", "cam_pos", "blur_px"}, ...]}`` (``blur_px``: the frame's motion blur
  (du, dv) in pixels; its length is on each COCO image as ``blur_px``), which ``ReplayCamera(folder)`` replays as ``last_truth``;
- ``annotations.json``: every object of every frame (people and vehicles: box,
  class, visible fraction, distance, ground sample distance) as a COCO
  detection dataset, so you can train on our renders with any COCO tooling
  (``pycocotools.coco.COCO(folder + "/annotations.json")``).

It flies nothing itself and returns the truth table as a pandas DataFrame.
"""

from __future__ import annotations

import json
import math
import os

import cv2
import numpy as np
import pandas as pd

from ..errors import ConfigError
from ..world.truth import CLASSES, Truth
from .annotations import coco_dataset

FORMATS = ("png", "jpg")


def export_dataset(records, folder, *, fmt: str = "png", prefix: str = "frame") -> None:
    """Write ``(t, frame, truth)`` records to ``folder`` as numbered images with
    truth.csv and truth.json (see the module docstring)."""
    if fmt not in FORMATS:
        raise ConfigError(f"export_dataset: fmt = {fmt!r} is not allowed; allowed: "
                          f"{', '.join(map(repr, FORMATS))}")
    folder = os.fspath(folder)
    if os.path.exists(folder) and not os.path.isdir(folder):
        raise ConfigError(f"export_dataset: folder = {folder!r} exists and is not a folder")
    os.makedirs(folder, exist_ok=True)
    rows, frames_json, coco, blur = [], [], [], []
    for i, rec in enumerate(records):
        try:
            t, frame, truth = rec
        except (TypeError, ValueError):
            raise ConfigError(f"export_dataset: records[{i}] = {type(rec).__name__} is not "
                              f"allowed; expected (t, frame, truth)") from None
        frame = np.asarray(frame)
        if frame.dtype != np.uint8 or frame.ndim != 3 or frame.shape[2] != 3 or 0 in frame.shape:
            raise ConfigError(f"export_dataset: records[{i}] frame has shape {frame.shape} and "
                              f"dtype {frame.dtype}; expected uint8 (height, width, 3) RGB")
        if truth is None:
            truth = Truth(float(t), np.zeros(0, dtype=int), np.zeros((0, 2)))
        if not isinstance(truth, Truth):
            raise ConfigError(f"export_dataset: records[{i}] truth = {truth!r} is not allowed; "
                              f"expected a Truth (camera.last_truth) or None")
        name = f"{prefix}_{i:05d}.{fmt}"
        if not cv2.imwrite(os.path.join(folder, name), cv2.cvtColor(frame, cv2.COLOR_RGB2BGR)):
            raise ConfigError(f"export_dataset: cannot write {os.path.join(folder, name)!r}")
        pix = [[round(float(u), 2), round(float(v), 2)] for u, v in truth.pixels]
        rows.append({"frame": i, "file": name, "t": float(t), "count": truth.count,
                     "pixels": json.dumps(pix)})
        frames_json.append({"frame": i, "file": name, "t": float(t), "count": truth.count,
                            "indices": [int(k) for k in truth.indices], "pixels": pix,
                            "cam_pos": [round(float(x), 4) for x in truth.cam_pos],
                            "blur_px": [round(float(x), 4) for x in truth.blur_px]})
        coco.append((name, frame.shape[1], frame.shape[0], truth.objects))
        blur.append(math.hypot(*truth.blur_px))
    df = pd.DataFrame(rows, columns=["frame", "file", "t", "count", "pixels"])
    df.to_csv(os.path.join(folder, "truth.csv"), index=False)
    with open(os.path.join(folder, "truth.json"), "w") as f:
        json.dump({"frames": frames_json}, f)
    classes = records[0][2].objects.classes if len(coco) and records[0][2] is not None else None
    with open(os.path.join(folder, "annotations.json"), "w") as f:
        json.dump(coco_dataset(coco, classes or CLASSES, blur=blur), f)
    return df
