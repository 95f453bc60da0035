"""Frames on the radio link: JPEG encoding and decoding with OpenCV, and the
annotated alert frame an on-board task sends when it sees a crowd."""

from __future__ import annotations

import cv2
import numpy as np

# JPEG encoding cost, MAC-equivalents per pixel. An estimate, not a measured
# figure: RGB->YCbCr ~9 multiply-adds, 4:2:0 chroma ~1, 8x8 forward DCT via the
# separable AAN algorithm ~5 per pixel per pass (~10), quantisation 1.5 and
# Huffman coding a few: ~20-25. libjpeg-turbo with SIMD is faster per op
# than a CNN runtime, so this tends to overestimate slightly.
JPEG_MACS_PER_PIXEL = 20


def encode_jpeg(frame, quality: int) -> bytes:
    """JPEG bytes of an RGB (or grey) uint8 frame, with OpenCV."""
    a = np.asarray(frame)
    if a.dtype != np.uint8:
        a = np.clip(a, 0, 255).astype(np.uint8)
    if a.ndim == 3 and a.shape[2] == 3:
        a = cv2.cvtColor(a, cv2.COLOR_RGB2BGR)
    elif a.ndim == 3 and a.shape[2] == 4:
        a = cv2.cvtColor(a, cv2.COLOR_RGBA2BGR)
    ok, buf = cv2.imencode(".jpg", a, [int(cv2.IMWRITE_JPEG_QUALITY), int(quality)])
    if not ok:  # pragma: no cover - OpenCV failure
        raise RuntimeError("cv2.imencode failed")
    return buf.tobytes()


def decode_jpeg(data: bytes, grey: bool) -> np.ndarray:
    """The image of JPEG ``data`` (RGB, or one channel when ``grey``)."""
    a = cv2.imdecode(np.frombuffer(data, np.uint8),
                     cv2.IMREAD_GRAYSCALE if grey else cv2.IMREAD_COLOR)
    if a is None:               # not a JPEG (encode_jpeg's own output always decodes)
        raise RuntimeError("cv2.imdecode failed")
    return a if grey else cv2.cvtColor(a, cv2.COLOR_BGR2RGB)


def is_image(value) -> bool:
    return (isinstance(value, np.ndarray) and value.dtype == np.uint8
            and (value.ndim == 2 or (value.ndim == 3 and value.shape[2] in (1, 3, 4))))


def annotate(frame, count, pos):
    """The alert frame: a red border and the count and position written on it."""
    a = np.array(frame, dtype=np.uint8, copy=True)
    h, w = a.shape[:2]
    cv2.rectangle(a, (2, 2), (w - 3, h - 3), (255, 0, 0), 2)
    cv2.putText(a, f"crowd {count:.0f} @ {pos[0]:.0f},{pos[1]:.0f},{pos[2]:.0f}", (6, 20),
                cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 0), 1, cv2.LINE_AA)
    return a
