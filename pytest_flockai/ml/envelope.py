"""Where a detector holds: a KPI mapped over two imaging axes.

``envelope(model, world, altitudes_m=..., speeds_mps=..., conditions=...)``
renders a fixed set of views of ``world`` at each altitude (``ViewSet``),
sees them under ``conditions`` with the camera moving at each speed during the
exposure, scores the model's detections against the truth (COCO, as a task
does) and returns a DataFrame with one row per (altitude, speed) cell and a
column per KPI. ``pytest_flockai.plots.save_envelope(df, path)`` writes it as
CSV and, with matplotlib installed, as a heat map next to it.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from .. import memo
from ..errors import ConfigError
from ..sensors.conditions import Conditions
from ..sensors.views import ViewSet
from ..world.truth import CLASSES
from .detections import parse_detections
from .evaluation import FrameRecord, detection_kpis


def envelope(model, world, *, altitudes_m=(15.0, 25.0, 35.0, 50.0), speeds_mps=(0.0, 5.0, 10.0, 15.0),
             conditions: Conditions | None = None, views: int = 8, seed: int = 0, camera=None,
             classes=CLASSES, score_threshold: float = 0.4, min_visible: float = 0.25,
             decode="auto", area=60.0) -> pd.DataFrame:
    """KPIs of ``model`` at each (altitude, speed) on ``views`` random views of ``world``
    (positions within ``area`` m of home, random headings, from the seed); memoised
    (``pytest_flockai.memo``) on every argument, the model's file bytes included."""
    cond = conditions if conditions is not None else Conditions(exposure_s=1 / 60)
    if not isinstance(cond, Conditions):
        raise ConfigError(f"envelope: conditions = {conditions!r} is not a fa.Conditions")
    args = dict(altitudes_m=altitudes_m, speeds_mps=speeds_mps, cond=cond, views=views, seed=seed,
                camera=camera, classes=classes, score_threshold=score_threshold,
                min_visible=min_visible, decode=decode, area=area)
    return memo.recall("envelope", {"model": model, "world": world, **args},
                       lambda: _envelope(model, world, **args),
                       pack=lambda df: {"columns": list(df.columns),
                                        "rows": df.to_numpy(dtype=float).tolist()},
                       unpack=lambda d: pd.DataFrame(d["rows"], columns=d["columns"]))


def _envelope(model, world, *, altitudes_m, speeds_mps, cond, views, seed, camera, classes,
              score_threshold, min_visible, decode, area) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    xy = rng.uniform(-area, area, size=(views, 2))
    yaw = rng.uniform(-math.pi, math.pi, size=views)
    rows = []
    for alt in altitudes_m:
        vs = ViewSet(world, [(x, y, float(alt), h) for (x, y), h in zip(xy, yaw)], camera,
                     depth=cond.needs_depth)
        for speed in speeds_mps:
            frames = vs.under(cond, velocity=(float(speed), 0.0, 0.0), seed=seed)
            recs = []
            for i, (f, t) in enumerate(frames):
                det = parse_detections(model(f), f.shape[:2], n_classes=len(classes),
                                       where="envelope", decode=decode, score_threshold=0.05,
                                       input_hw=getattr(model, "input_size", None))
                recs.append(FrameRecord(i, t.objects, det, float(alt), f.shape[1], f.shape[0]))
            k = detection_kpis(recs, tuple(classes), score_threshold=score_threshold,
                               min_visible=min_visible)
            blur = float(np.mean([math.hypot(*t.blur_px) for _, t in frames]))
            rows.append({"altitude_m": float(alt), "speed_mps": float(speed), "blur_px": blur, **k})
    return pd.DataFrame(rows)


def altitude_band(df: pd.DataFrame, kpi: str, limit: float, *, speed_mps: float):
    """(lowest, highest) altitude of the longest run of consecutive altitudes at which
    ``kpi >= limit`` at ``speed_mps``; (NaN, NaN) when it holds nowhere."""
    sel = df[df["speed_mps"] == speed_mps].sort_values("altitude_m")
    runs, run = [], []
    for alt, v in zip(sel["altitude_m"], sel[kpi]):
        if v >= limit:
            run.append(float(alt))
        elif run:
            runs.append(run)
            run = []
    if run:
        runs.append(run)
    if not runs:
        return math.nan, math.nan
    best = max(runs, key=len)
    return best[0], best[-1]
