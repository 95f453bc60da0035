"""PR curves, per-class AP, the confusion matrix and the F1-best threshold are
COCOeval's own numbers: the files a task writes (COCO truth + results), loaded into
pycocotools by hand, give the same precision array and stats; the confusion matrix
counts the mistakes the model was built to make."""

import contextlib
import io
import json

import numpy as np
import pytest
from labelled_sets import CELL, make_set
from pycocotools.coco import COCO
from pycocotools.cocoeval import COCOeval

import pytest_flockai as fa
from pytest_flockai.ml import PythonModel


def flawed_model(sc):
    """Drops box k of image i when (i + k) % 5 == 0, calls the vehicle a person on every
    fourth image, adds a person on background every third image; scores vary."""
    def model(frame):
        i = int(frame[-1, -1, 0])
        boxes, cell = sc[i]
        rows = []
        for k, (c, x, y, w, h) in enumerate(boxes):
            if (i + k) % 5 == 0:
                continue
            c = 0 if (c == 1 and i % 4 == 0) else c
            rows.append([x, y, x + w, y + h, 0.3 + 0.6 * ((3 * i + k) % 7) / 6, c])
        if i % 3 == 0:
            rows.append([cell[0], cell[1], cell[0] + CELL, cell[1] + CELL, 0.5, 0])
        return np.array(rows, dtype=float).reshape(-1, 6)
    return model


@pytest.fixture(scope="module")
def evaluated(tmp_path_factory):
    root = tmp_path_factory.mktemp("set")
    path, sc = make_set(root, "coco", n=40)
    task = fa.Task(PythonModel(flawed_model(sc), macs=1e6), evaluate="detection", name="det")
    return fa.ml.evaluate_dataset(task, path), sc


def test_pr_curves_and_ap_equal_cocoevals_arrays_from_the_written_files(evaluated, tmp_path):
    ev, _ = evaluated
    paths = ev.write_results(tmp_path)
    with contextlib.redirect_stdout(io.StringIO()):
        gt = COCO(paths["truth"])
        dt = gt.loadRes(paths["results"])
        ref = COCOeval(gt, dt, "bbox")
        ref.params.maxDets = [10, 100, 1000]
        ref.params.areaRng, ref.params.areaRngLbl = [[0, 1e10]], ["all"]
        ref.evaluate()
        ref.accumulate()
        ref.summarize()
    a = ev.analysis()
    for k, c in enumerate(("person", "vehicle")):
        assert a["pr_curves"][c] == ref.eval["precision"][0, :, k, 0, -1].tolist()
        assert a["scores"][c] == ref.eval["scores"][0, :, k, 0, -1].tolist()
        assert a["ap"][c]["ap50"] == pytest.approx(ev.kpis[f"map50.{c}"], abs=1e-12)
    assert a["stats"] == ref.stats.tolist()
    assert a["stats"][0] == pytest.approx(ev.kpis["map50_95"], abs=1e-12)
    assert a["stats"][1] == pytest.approx(ev.kpis["map50"], abs=1e-12)
    assert 0.3 < ev.kpis["map50"] < 0.95
    assert len(json.loads(open(paths["results"]).read())) > 80


def test_the_confusion_matrix_counts_the_models_mistakes(evaluated):
    ev, sc = evaluated
    m = np.array(ev.analysis()["confusion"]["matrix"])         # rows truth, columns predicted
    n = len(sc)
    kept = lambda i, k: (i + k) % 5 != 0                        # noqa: E731
    flipped = sum(kept(i, 2) for i in range(n) if i % 4 == 0)
    assert m[1, 0] == flipped                                  # vehicles called people
    assert m[1, 1] == sum(kept(i, 2) for i in range(n) if i % 4 != 0)
    assert m[0, 0] == sum(kept(i, k) for i in range(n) for k in (0, 1))
    assert m[2, 0] == len(range(0, n, 3)) and m[2, 1] == 0      # people on background
    assert m[0, 2] == sum(not kept(i, k) for i in range(n) for k in (0, 1))
    assert m[1, 2] == sum(not kept(i, 2) for i in range(n))    # missed vehicles


def test_the_f1_best_threshold_is_a_score_on_the_curve(evaluated):
    ev, _ = evaluated
    a = ev.analysis()
    for c in ("person", "vehicle", "all"):
        best = a["f1_best"][c]
        assert 0.3 <= best["threshold"] <= 0.9
        p, r = best["precision"], best["recall"]
        assert best["f1"] == pytest.approx(2 * p * r / (p + r))
    curve = np.array(a["pr_curves"]["person"])
    r = np.array(a["recall_thresholds"])
    f1 = np.where(curve > 0, 2 * curve * r / np.maximum(curve + r, 1e-12), -1)
    assert a["f1_best"]["person"]["f1"] == pytest.approx(f1.max())
