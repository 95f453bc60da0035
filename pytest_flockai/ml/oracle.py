"""The oracle model: the frame's truth boxes as detections, optionally degraded.

``Oracle`` bounds what an application could do with a perfect (or a given-quality)
detector before it has one. It needs no pixels: a task whose models are all
oracles never renders a frame; its model receives an ``OracleFrame`` (the frame's
per-object truth, its image size and a random stream spawned from the mission
seed) instead of an image, and returns an (N, 6) array ``x0, y0, x1, y1, score,
class`` like any detector (``ml.detections``).

Degradations, each drawn per frame from the mission seed: ``miss_rate`` (each
object is missed with this probability), ``box_noise_px`` (Gaussian noise, this
standard deviation in pixels, on every box edge), ``false_positives`` (mean number
of spurious boxes per frame, Poisson, uniform over the image, 20 to 60 px wide)
and ``delay_s`` (the result reaches the drone this much later; the computer is
not busy for it: a pipeline or transport delay). ``macs`` charges the computer as
a real model of that cost would (default 0: only the device's fixed overhead), so
energy and busy time can be bounded without the model.
"""

from __future__ import annotations

import numpy as np

from .. import _check, limits
from ..errors import ConfigError
from ..world.truth import CLASSES
from .models import Model, _check_macs


class OracleFrame:
    """What an oracle sees instead of pixels: ``truth`` (a ``world.truth.Truth``),
    ``shape`` (height, width, 3) of the frame it stands for, and ``rng``."""

    __slots__ = ("truth", "shape", "rng")

    def __init__(self, truth, shape, rng):
        self.truth, self.shape, self.rng = truth, tuple(shape), rng


class Oracle(Model):
    """Truth boxes as detections (see the module docstring). ``classes``: which
    object classes it reports (names of ``world.truth.CLASSES``); ``min_visible``:
    objects less visible than this are not reported; ``score``: the score given."""

    needs_pixels = False

    def __init__(self, *, classes=CLASSES, miss_rate: float = 0.0, box_noise_px: float = 0.0,
                 false_positives: float = 0.0, delay_s: float = 0.0, macs: int = 0,
                 min_visible: float = 0.25, score: float = 0.9, name: str = "oracle"):
        where = f"Oracle {name!r}"
        try:
            names = tuple(str(c) for c in classes)
        except TypeError:
            raise ConfigError(f"{where}: classes = {classes!r} is not a list of class names") from None
        bad = [c for c in names if c not in CLASSES]
        if bad or not names:
            raise ConfigError(f"{where}: classes = {classes!r} is not allowed; allowed: names "
                              f"from {', '.join(map(repr, CLASSES))}")
        self.classes = names
        self._keep = np.array([CLASSES.index(c) for c in names])
        self.miss_rate = _check.fraction("miss_rate", miss_rate, where=where)
        self.box_noise_px = _check.non_negative("box_noise_px", box_noise_px, where=where)
        self.false_positives = _check.non_negative("false_positives", false_positives, where=where)
        limits.check_at_most("false_positives", self.false_positives,
                             "MAX_ORACLE_FALSE_POSITIVES", where=where, unit=" per frame")
        self.delay_s = _check.non_negative("delay_s", delay_s, where=where)
        self.macs = _check_macs(macs, where, allow_none=False)
        self.min_visible = _check.fraction("min_visible", min_visible, where=where)
        self.score = _check.fraction("score", score, where=where)
        self.name = name
        self.params = 0

    def __call__(self, frame) -> np.ndarray:
        if not isinstance(frame, OracleFrame):
            raise ConfigError(f"Oracle {self.name!r} needs the frame's truth, got "
                              f"{type(frame).__name__}; run it as a Task on a camera")
        objs, rng = frame.truth.objects, frame.rng
        h, w = frame.shape[0], frame.shape[1]
        keep = np.isin(objs.cls, self._keep) & (objs.visible >= self.min_visible)
        boxes, cls = objs.boxes[keep].astype(float), objs.cls[keep]
        if self.miss_rate > 0.0 and len(boxes):
            hit = rng.random(len(boxes)) >= self.miss_rate
            boxes, cls = boxes[hit], cls[hit]
        if self.box_noise_px > 0.0 and len(boxes):
            boxes = boxes + rng.normal(0.0, self.box_noise_px, boxes.shape)
        rows = [np.column_stack([boxes, np.full(len(boxes), self.score), cls])]
        if self.false_positives > 0.0:
            n = int(rng.poisson(self.false_positives))
            size = rng.uniform(20.0, 60.0, (n, 2))
            x0 = rng.uniform(0.0, max(w - 20.0, 1.0), n)
            y0 = rng.uniform(0.0, max(h - 20.0, 1.0), n)
            fc = rng.choice(self._keep, n)
            rows.append(np.column_stack([x0, y0, x0 + size[:, 0], y0 + size[:, 1],
                                         np.full(n, self.score), fc]))
        out = np.vstack(rows).reshape(-1, 6)
        out[:, [0, 2]] = np.clip(out[:, [0, 2]], 0.0, w)
        out[:, [1, 3]] = np.clip(out[:, [1, 3]], 0.0, h)
        return out[(out[:, 2] > out[:, 0]) & (out[:, 3] > out[:, 1])]

    def to_dict(self) -> dict:
        """The fields as a JSON-ready dict."""
        return {"type": "Oracle", "classes": list(self.classes), "miss_rate": self.miss_rate,
                "box_noise_px": self.box_noise_px, "false_positives": self.false_positives,
                "delay_s": self.delay_s, "macs": self.macs, "min_visible": self.min_visible,
                "score": self.score}

    def __repr__(self):
        args = ", ".join(f"{k}={v!r}" for k, v in self.to_dict().items() if k != "type")
        return f"Oracle({args})"


def needs_pixels(model) -> bool:
    """False for models that read the truth instead of the image (``Oracle``)."""
    return bool(getattr(model, "needs_pixels", True))


__all__ = ["Oracle", "OracleFrame", "needs_pixels"]
