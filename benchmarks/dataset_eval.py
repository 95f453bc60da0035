"""Dataset mode and the ML analyses: what they cost.

    MUJOCO_GL=egl python benchmarks/dataset_eval.py

Prints, median of 5: ``fa.ml.evaluate_dataset`` over a 40-image COCO folder (160x128
synthetic frames, a PythonModel that returns boxes: the reading, scoring and COCOeval
cost, not a model's), ``analysis()`` (two COCOeval runs), ``gallery(6)`` (COCOeval
matches, drawing, PNG); and the JPEG a detection task keeps per rendered frame for its
gallery (320x240, quality 85: a rendered frame, and noise as the worst case).
"""

from __future__ import annotations

import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from labelled_sets import make_set  # noqa: E402
from test_detection_analysis import flawed_model  # noqa: E402

import pytest_flockai as fa  # noqa: E402
from pytest_flockai.ml.jpeg import encode_jpeg  # noqa: E402
from pytest_flockai.sensors import render_views  # noqa: E402


def _median(fn, n=5) -> float:
    out = []
    for _ in range(n):
        t0 = time.perf_counter()
        fn()
        out.append(time.perf_counter() - t0)
    return statistics.median(out)


def main() -> None:
    tmp = Path(tempfile.mkdtemp())
    path, sc = make_set(tmp, "coco", n=40)
    task = fa.Task(fa.ml.PythonModel(flawed_model(sc), macs=1), evaluate="detection", name="det")
    ev = fa.ml.evaluate_dataset(task, path)
    print(f"evaluate_dataset, 40 images: {_median(lambda: fa.ml.evaluate_dataset(task, path)):.3f} s")
    print(f"analysis(): {_median(ev.analysis):.3f} s")
    print(f"gallery(6): {_median(lambda: ev.gallery(6)):.3f} s")
    w = fa.World.urban(seed=3, size=(80.0, 80.0), people=40)
    (frame, _), = render_views(w, [(0.0, 0.0, 25.0, 0.0)], {"fov_deg": 51.0})
    noise = np.random.default_rng(0).integers(0, 255, frame.shape, dtype=np.uint8)
    for name, f in (("rendered", frame), ("noise", noise)):
        per = _median(lambda f=f: [encode_jpeg(f, 85) for _ in range(100)]) / 100
        print(f"gallery JPEG per {name} 320x240 frame: {per * 1e3:.2f} ms")


if __name__ == "__main__":
    main()
