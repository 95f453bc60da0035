"""Accuracy and latency metrics of ML tasks.

Crowd detection (the paper's use case, section 5): a frame *shows a crowd*
when its true people count is >= ``threshold``; the model *detects a crowd*
when its predicted count is >= the same ``threshold``. Per inferred frame
this gives true/false positives and negatives, hence precision and recall.

``detection_delay_frames`` follows the paper's Table 4 ("inference delay":
the index of the first frame of a sequence from which the crowd is
detected): a *crowd encounter* is a run of consecutive frames showing a
crowd; its delay is the number of frames from the first frame of the run to
the first frame whose inference detected the crowd (0: detected on the frame
the crowd entered view; the paper's 1-based index is ours + 1). Frames that
were dropped or whose inference failed count as not detected. Encounters
never detected (the paper's "-") are left out of the mean and counted in
``crowds_missed``.
"""

from __future__ import annotations

import bisect
import math
from numbers import Real

import numpy as np


def count_of(prediction):
    """The people count a prediction stands for, or None.

    numbers -> the number; ``{"count": n}`` -> n; list/tuple -> its length
    (a list of detections); array of size 1 -> its value; any other array ->
    its sum (a density map). Give ``Task(count=...)`` for anything else (e.g.
    an N x 5 box array: ``count=len``).
    """
    if prediction is None:
        return None
    if isinstance(prediction, (bool, np.bool_)):
        return float(prediction)
    if isinstance(prediction, Real):
        return float(prediction)
    if isinstance(prediction, dict):
        c = prediction.get("count")
        return None if c is None else float(c)
    if isinstance(prediction, (list, tuple)):
        return float(len(prediction))
    if isinstance(prediction, np.ndarray):
        if prediction.size == 1:
            return float(prediction.reshape(-1)[0])
        return float(prediction.sum(dtype=np.float64))
    return None


def truth_count(truth):
    """Count of the people in view from the mission's truth (None: unknown)."""
    if truth is None:
        return None
    if hasattr(truth, "count") and not isinstance(truth, (list, tuple, np.ndarray)):
        return float(truth.count)             # a camera frame's Truth
    if isinstance(truth, Real) and not isinstance(truth, bool):
        return float(truth)
    try:
        return float(len(truth))
    except TypeError:
        return None


def percentile(values, q: float) -> float:
    if len(values) == 0:
        return math.nan
    return float(np.percentile(np.asarray(values, dtype=np.float64), q))


class SortedValues:
    """Values kept sorted as they arrive, so a percentile costs O(1) at any time in a
    flight (the probes read the latency percentiles every sample: recomputing them over
    every inference so far made a 30-minute 5 Hz task quadratic). ``percentile`` gives
    ``percentile()``'s number bit for bit: NumPy's linear method, step for step
    (``tests/ml/test_latency_percentiles.py`` checks it against NumPy)."""

    def __init__(self) -> None:
        self._v: list[float] = []

    def add(self, value: float) -> None:
        bisect.insort(self._v, float(value))

    def __len__(self) -> int:
        return len(self._v)

    def max(self) -> float:
        return self._v[-1] if self._v else math.nan

    def percentile(self, q: float) -> float:
        v, n = self._v, len(self._v)
        if n == 0:
            return math.nan
        virtual = (n - 1) * (q / 100)             # numpy: (n - 1) * quantile
        lo = min(max(math.floor(virtual), 0), n - 1)
        gamma = virtual - lo
        a, b = v[lo], v[min(lo + 1, n - 1)]
        diff = b - a                              # numpy's _lerp, both branches
        return b - diff * (1 - gamma) if gamma >= 0.5 else a + diff * gamma


def crowd_metrics(truth, pred, threshold: float) -> dict:
    """Accuracy from per-frame arrays (NaN where unknown / not inferred).

    ``truth[i]``: true count of frame i (NaN: no truth); ``pred[i]``: predicted
    count of frame i (NaN: dropped, failed or not yet done). Returns
    count_mae, detection_precision, detection_recall, detection_delay_frames
    (NaN when undefined) and crowd_encounters, crowds_missed, inferred_frames.
    """
    truth = np.asarray(truth, dtype=np.float64)
    pred = np.asarray(pred, dtype=np.float64)
    both = ~np.isnan(truth) & ~np.isnan(pred)
    out: dict[str, float] = {"inferred_frames": int(both.sum())}
    if both.any():
        t, p = truth[both], pred[both]
        out["count_mae"] = float(np.mean(np.abs(p - t)))
        tp = int(np.sum((p >= threshold) & (t >= threshold)))
        fp = int(np.sum((p >= threshold) & (t < threshold)))
        fn = int(np.sum((p < threshold) & (t >= threshold)))
        out["detection_precision"] = tp / (tp + fp) if tp + fp else math.nan
        out["detection_recall"] = tp / (tp + fn) if tp + fn else math.nan
    else:
        out["count_mae"] = out["detection_precision"] = out["detection_recall"] = math.nan
    crowd = ~np.isnan(truth) & (np.nan_to_num(truth, nan=-1.0) >= threshold)
    detected = ~np.isnan(pred) & (np.nan_to_num(pred, nan=-1.0) >= threshold)
    delays, encounters, missed = [], 0, 0
    i, n = 0, len(truth)
    while i < n:
        if not crowd[i]:
            i += 1
            continue
        j = i
        while j < n and crowd[j]:
            j += 1
        encounters += 1
        hits = np.flatnonzero(detected[i:j])
        if hits.size:
            delays.append(int(hits[0]))
        else:
            missed += 1
        i = j
    out["detection_delay_frames"] = float(np.mean(delays)) if delays else math.nan
    out["crowd_encounters"] = encounters
    out["crowds_missed"] = missed
    return out


def invalid_prediction(pred, count, task, reason: str | None = None) -> str | None:
    """Why a prediction is not a valid result (it then counts as a failed
    inference), or None: None, a count that is not a finite number >= 0 (NaN,
    inf, negative), nothing countable where the task scores counts, or
    ``reason`` (a detection output that could not be parsed)."""
    if pred is None:
        return "invalid prediction: the model returned None"
    if reason is not None:
        return f"invalid prediction: {reason}"
    if count is not None and not (math.isfinite(count) and count >= 0):
        return f"invalid prediction {_short(pred)}: count {count!r} is not a finite number >= 0"
    if count is None and task.evaluate == "count":
        return (f"invalid prediction {_short(pred)}: no people count in it (expected a number, an "
                f"array, a list of detections or {{'count': n}}; Task(count=...) reads other shapes)")
    return None


def _short(pred) -> str:
    text = repr(pred)
    return text if len(text) <= 60 else text[:57] + "..."


__all__ = ["count_of", "crowd_metrics", "invalid_prediction", "percentile", "truth_count"]
