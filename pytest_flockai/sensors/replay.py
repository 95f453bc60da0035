"""Replayed camera: frames from a folder of images or a video file.

``ReplayCamera(path, rate_hz=1.0, loop=True)`` has the camera's interface
(``read(t, data) -> frame``, ``last_frame``, ``last_truth``, ``on_demand``):
the recording starts at the first read (``t_start``: the first tick of the task
that reads it, whenever the task starts after take-off): frame 0 is shown from
then until the next whole frame period of the mission clock (``j / rate_hz``),
frame k for the k-th period after it (the stated rate, whatever the video's own
frame rate). A task with
``period_s = 1 / rate_hz`` and ``loop=False`` scores every image exactly once, and
after the last one the task stops taking frames (no inference, no failure). With ``loop`` the recording starts again after its
last frame; without, ``read`` returns None after the end (``ended`` is True).

Folder (or an Ultralytics data.yaml): the images (.png .jpg .jpeg .bmp .tif
.tiff .webp) sorted by file name, decoded on demand (one frame cached), with
their labels in any layout ``labelsets`` reads (COCO, YOLO flat or images/ +
labels/, data.yaml with ``split``, VisDrone-DET); ``last_file`` is the image shown. If the folder holds the
``truth.json`` written by ``export_dataset``, ``last_truth`` replays it.
Video: read in order with OpenCV; going back (a loop) reopens the file.
Frames are RGB uint8 (OpenCV's BGR is converted), like the rendered camera.
"""

from __future__ import annotations

import json
import math
import os
from typing import Any

import cv2
import numpy as np

from .. import _check
from ..errors import ConfigError
from ..world.truth import Objects, Truth
from . import replay_conditions as _conditions
from .annotations import load_annotations, orphan_labels
from .base import DroneBody, Sensor
from .classnames import person_index
from .labelsets import IMAGE_EXT, find_labelset, regular

#: frames of slack when the clock picks a frame: a read a hair before a frame's
#: start (floating-point sums of the tick) still shows it
FRAME_TOL = 1e-6


class ReplayCamera(Sensor):
    """A camera that shows recorded frames: a folder of images (with COCO, YOLO or
    VisDrone-DET labels, scored by a detection task) or a video file.

    ``rate_hz``: frames per second of the mission clock, from the task's first read;
    ``loop=False`` shows each image once (a task with ``period_s = 1 / rate_hz`` scores
    each once); ``annotations``, ``split`` and ``classes`` choose the labels (see
    ``sensors.labelsets``); ``conditions`` applies what a recorded frame allows (blur,
    light, noise, weather; not haze or a new sun direction)."""

    on_demand = True

    def __init__(self, path, rate_hz: float = 1.0, loop: bool = True, *, name: str = "camera",
                 power_w: float = 0.9, annotations="auto", classes=None, split=None,
                 conditions=None, fov_deg: float = 51.0, body_name: str = "drone"):
        super().__init__(name, rate_hz=rate_hz, power_w=power_w)
        w = f"ReplayCamera {name!r}"
        self.conditions = _conditions.check(conditions, w)
        self.fov_deg = _check.number("fov_deg", fov_deg, where=w, minimum=1.0, maximum=179.0)
        self.body_name, self._body = body_name, None
        p = os.fspath(path)
        self.path, self.loop = p, bool(loop)
        self.files = None
        self._cap = None
        self._truth = None
        if os.path.isdir(p) or p.lower().endswith((".yaml", ".yml")) and os.path.isfile(p):
            ls = find_labelset(p, fmt=annotations, split=split, where=w)
            self.files, self.labels = ls.images, ls
            if not self.files:
                raise ConfigError(f"{w}: path = {p!r} holds no images; allowed extensions: "
                                  f"{', '.join(IMAGE_EXT)}")
            first = cv2.imread(self.files[0], cv2.IMREAD_COLOR)
            if first is None:
                raise ConfigError(f"{w}: image {self.files[0]!r} cannot be decoded")
            self.n_frames: int | None = len(self.files)
            self.height, self.width = first.shape[:2]
            tj = os.path.join(p, "truth.json")
            if regular(tj, w):
                self._truth, named = _load_truth(tj, w)
                _check_truth_files(tj, named, self.files, w)
                if len(self._truth) != len(self.files):
                    raise ConfigError(
                        f"{w}: {tj!r} has {len(self._truth)} frame(s) for the folder's "
                        f"{len(self.files)} image(s) (first not covered: "
                        f"{os.path.basename(self.files[min(len(self._truth), len(self.files) - 1)])!r}"
                        f"); export_dataset writes one frame per image: re-export, or move the "
                        f"truth.json out to score the images by their labels")
            self._attach_objects(ls, classes, w)
            for f, tr in zip(self.files, self._truth or ()):
                tr.file = f         # the image a frame record shows (galleries, results)
        elif os.path.isfile(p):
            cap = cv2.VideoCapture(p)
            if not cap.isOpened():
                raise ConfigError(f"{w}: path = {p!r} is not a readable video (OpenCV "
                                  f"VideoCapture cannot open it)")
            self.width = int(cap.get(cv2.CAP_PROP_FRAME_WIDTH))
            self.height = int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT))
            n = int(cap.get(cv2.CAP_PROP_FRAME_COUNT))
            cap.release()
            self.n_frames = n if n > 0 else None     # unknown: found at the end
        else:
            raise ConfigError(f"{w}: path = {p!r}: no such folder or video file (nor an Ultralytics data.yaml)")
        if self.width <= 0 or self.height <= 0:
            raise ConfigError(f"{w}: path = {p!r} has resolution {self.width}x{self.height}; "
                              f"expected width and height > 0")
        self.last_frame: np.ndarray | None = None
        self.last_truth: Any = None
        self.last_t: float | None = None
        self.last_file: str | None = None
        self.frames = 0
        self.ended = False
        self.t_start: float | None = None     # the first read: the recording's frame 0
        self.last_blur_px = (0.0, 0.0)
        self._k = -1            # index of the cached frame
        self._pos = 0           # next frame the video capture will decode

    def _attach_objects(self, ls, classes, where):
        """Per-object truth of each image from its labels (``labelsets`` finds them)."""
        if ls.fmt is None:
            return
        orphans = orphan_labels(ls.label_dir, self.files) if ls.fmt != "coco" else []
        if orphans:
            raise ConfigError(f"{where}: label file {orphans[0]!r} has no image in "
                              f"{ls.label_dir!r}")
        sizes = [_image_size(f, where) for f in self.files]
        objs, names = load_annotations(ls, sizes, classes=classes, where=where)
        if self._truth is None:
            person = person_index(names)
            self._truth = [_truth_of(k, o, person) for k, o in enumerate(objs)]
        else:
            for tr, o in zip(self._truth, objs):
                tr.objects = o

    def bind(self, model, data, rng):
        super().bind(model, data, rng)
        if self.conditions is not None and model is not None:
            self._body = DroneBody(model, self.body_name, f"ReplayCamera {self.name!r}").id
        self.last_frame = self.last_truth = self.last_t = self.last_file = None
        self.frames = 0
        self.ended = False
        self.t_start = None

    def frame_index(self, t: float) -> int | None:
        """Index of the recording's frame shown at time t (None: after the end, no
        loop); frame 0 at the first read (see the module docstring)."""
        k0 = 0 if self.t_start is None else math.floor(self.t_start * self.rate_hz + FRAME_TOL)
        k = int(math.floor(t * self.rate_hz + FRAME_TOL)) - k0
        k = max(k, 0)
        n = self.n_frames
        if n is None:
            return k
        if k >= n:
            return k % n if self.loop else None
        return k

    def read(self, t: float, data=None):
        if self.t_start is None:
            self.t_start = float(t)
        k = self.frame_index(t)
        if k is not None and self.files is None:
            frame = self._video_frame(k)
            if frame is None:          # the video ended earlier than its header said
                k = self.frame_index(t)
                frame = self._video_frame(k) if k is not None else None
        elif k is not None:
            frame = self._image(k)
        else:
            frame = None
        if frame is None:
            self.ended = True
            self.last_frame, self.last_t, self.last_truth = None, float(t), None
            return None
        self.last_truth = None
        if self._truth is not None and k is not None and k < len(self._truth):
            self.last_truth = self._truth[k]
        if self.conditions is not None and self._body is not None and data is not None:
            frame, self.last_blur_px = _conditions.condition(
                frame, self.conditions, self.rng, data, self._body, self.fov_deg, self.last_truth)
        self.last_frame, self.last_t = frame, float(t)
        self.last_file = self.files[k] if self.files is not None and k is not None else None
        self.frames += 1
        return frame

    # -- decoding -------------------------------------------------------------
    def _image(self, k):
        if k != self._k:
            img = cv2.imread(self.files[k], cv2.IMREAD_COLOR)
            if img is None:
                raise ConfigError(f"ReplayCamera {self.name!r}: image {self.files[k]!r} cannot "
                                  f"be decoded")
            self._frame = cv2.cvtColor(img, cv2.COLOR_BGR2RGB)
            self._k = k
        return self._frame

    def _video_frame(self, k):
        if k == self._k:
            return self._frame
        if self._cap is None or k < self._pos:
            if self._cap is not None:
                self._cap.release()
            self._cap = cv2.VideoCapture(self.path)
            self._pos = 0
        img = None
        while self._pos <= k:
            ok, img = self._cap.read()
            if not ok:
                # the real length: remember it so the next index wraps (or ends)
                self.n_frames = self._pos
                self._cap.release()
                self._cap = None
                self._k = -1
                if self._pos == 0:
                    raise ConfigError(f"ReplayCamera {self.name!r}: video {self.path!r} has "
                                      f"no readable frames")
                return None
            self._pos += 1
        self._frame = cv2.cvtColor(img, cv2.COLOR_BGR2RGB)
        self._k = k
        return self._frame

    def close(self) -> None:
        """Release the video file (a folder holds nothing open)."""
        if self._cap is not None:
            self._cap.release()
            self._cap = None

    def to_dict(self):
        return {**super().to_dict(), "path": self.path, "loop": self.loop,
                "frames": self.n_frames, "width": self.width, "height": self.height,
                **({"conditions": self.conditions.to_dict(), "fov_deg": self.fov_deg}
                   if self.conditions is not None else {})}

    def __repr__(self):
        return f"ReplayCamera({self.path!r}, rate_hz={self.rate_hz:g}, loop={self.loop})"


def _image_size(path, where):
    img = cv2.imread(path, cv2.IMREAD_UNCHANGED)
    if img is None:
        raise ConfigError(f"{where}: image {path!r} cannot be decoded")
    return int(img.shape[1]), int(img.shape[0])


def _truth_of(k, objs: Objects, person) -> Truth:
    """A frame's Truth from its labels: the people are the 'person' boxes (and its
    aliases: pedestrian, people), by their centres."""
    mask = np.isin(objs.cls, person)
    b = objs.boxes[mask]
    centres = np.column_stack([(b[:, 0] + b[:, 2]) / 2, (b[:, 1] + b[:, 3]) / 2]) if len(b) else np.zeros((0, 2))
    return Truth(float(k), np.flatnonzero(mask), centres, objects=objs)


def _load_truth(path, where):
    try:
        with open(path, encoding="utf-8") as f:
            rows = json.load(f)["frames"]
        return [Truth(float(r.get("t", 0.0)), np.array(r["indices"], dtype=int),
                      np.array(r["pixels"], dtype=float).reshape(-1, 2),
                      np.array(r.get("cam_pos", (np.nan,) * 3), dtype=float),
                      blur_px=tuple(r.get("blur_px", (0.0, 0.0)))) for r in rows], \
            [r.get("file") for r in rows]
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise ConfigError(f"{where}: {path!r} is not a truth file written by export_dataset: "
                          f"{exc}") from None


def _check_truth_files(path, named, files, where):
    """ConfigError when a frame of truth.json names another image than the folder's
    image at its place (images sorted by name, as export_dataset wrote them)."""
    for k, (name, f) in enumerate(zip(named, files)):
        if isinstance(name, str) and os.path.basename(name) != os.path.basename(f):
            raise ConfigError(f"{where}: {path!r} frames[{k}] file = {name!r} is not the "
                              f"folder's image {k} ({os.path.basename(f)!r}); truth.json must "
                              f"cover the folder's images in name order")
