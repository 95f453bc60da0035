"""A fiducial-marker detector: OpenCV's ArUco detector as a model of the loop.

``MarkerDetector(dictionary="DICT_4X4_50")`` runs ``cv2.aruco.ArucoDetector`` on the
rendered frame and returns an (N, 6) array ``x0, y0, x1, y1, score, class``: the
box of each found marker's corners, score 1, class 0 (give the task
``classes=("marker",)``).

Cost: ``MACS_PER_PIXEL`` = 60 operations per pixel, an estimate from what
``detectMarkers`` does with its default parameters: greyscale conversion (~3 per
pixel), adaptive thresholding at 3 window sizes (3, 13 and 23 px, a box filter and
a compare each: ~3 x 10), contour following and polygon approximation on the
thresholded images (~3 x 8), then perspective removal of the few candidates
(negligible at this scale).
"""

from __future__ import annotations

import cv2
import numpy as np

from ..errors import ConfigError
from ..world.aruco import DICTIONARIES, aruco_dictionary
from .models import Model

MACS_PER_PIXEL = 60


class MarkerDetector(Model):
    """ArUco markers in a frame (see the module docstring); ``marker_id``: report only
    this id (None: every marker of the dictionary)."""

    def __init__(self, dictionary: str = "DICT_4X4_50", *, marker_id: int | None = None,
                 width: int = 320, height: int = 240, name: str = "aruco"):
        if dictionary not in DICTIONARIES:
            raise ConfigError(f"MarkerDetector: dictionary = {dictionary!r} is not allowed; "
                              f"allowed: {', '.join(map(repr, DICTIONARIES))}")
        self.dictionary, self.marker_id, self.name = dictionary, marker_id, name
        self.macs = MACS_PER_PIXEL * int(width) * int(height)
        self.params = 0

    def bind_detector(self):
        """OpenCV's detector, made on the first frame (not part of the flight-cache key)."""
        self._det = cv2.aruco.ArucoDetector(aruco_dictionary(self.dictionary),
                                            cv2.aruco.DetectorParameters())
        return self._det

    def macs_for(self, frame) -> int:
        h, w = np.shape(frame)[:2]
        return MACS_PER_PIXEL * int(h) * int(w)

    def __call__(self, frame) -> np.ndarray:
        a = np.asarray(frame)
        grey = cv2.cvtColor(a, cv2.COLOR_RGB2GRAY) if a.ndim == 3 else a
        det = getattr(self, "_det", None) or self.bind_detector()
        corners, ids, _ = det.detectMarkers(grey)
        rows = []
        for c, i in zip(corners, ids.reshape(-1) if ids is not None else []):
            if self.marker_id is not None and int(i) != self.marker_id:
                continue
            pts = c.reshape(4, 2)
            lo, hi = pts.min(axis=0), pts.max(axis=0)
            rows.append((lo[0], lo[1], hi[0], hi[1], 1.0, 0.0))
        return np.asarray(rows, dtype=float).reshape(-1, 6)

    def to_dict(self) -> dict:
        """The fields as a JSON-ready dict."""
        return {"type": "MarkerDetector", "dictionary": self.dictionary,
                "marker_id": self.marker_id, "macs": self.macs}


__all__ = ["MACS_PER_PIXEL", "MarkerDetector"]
