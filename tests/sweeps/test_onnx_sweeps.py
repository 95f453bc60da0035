"""Sweeps and fleets carry real ONNX models: an ``OnnxModel`` is deep-copied and
pickled without its ONNX Runtime session (re-opened from the model's path), so
``fa.sweep`` of a mission with an ONNX detection task flies, and two worker
processes give the same rows as one."""

import copy
import pickle
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from labelled_sets import make_set

import pytest_flockai as fa

MODELS = Path(__file__).resolve().parents[2] / "fixtures" / "models"
WORLD = dict(seed=3, size=(80.0, 80.0), people=40, vehicles=10, max_building_height=10.0)


def _mission():
    det = fa.ml.OnnxModel(MODELS / "detector.onnx", name="detector")
    task = fa.Task(det, period_s=1.0, evaluate="detection", name="det", score_threshold=0.3)
    return fa.Mission(fa.drone("dji-mavic-2-pro"), fa.pilots.Hover(altitude=20.0, duration=3.0),
                      world=fa.World.urban(**WORLD), tasks=[task], until=12.0)


def test_an_onnx_model_survives_a_deep_copy_and_a_pickle_with_the_same_outputs():
    model = fa.ml.OnnxModel(MODELS / "detector.onnx", name="detector")
    frame = np.random.default_rng(0).integers(0, 255, (240, 320, 3), dtype=np.uint8)
    want = model(frame)
    for other in (copy.deepcopy(model), pickle.loads(pickle.dumps(model))):
        assert other.session is not model.session
        assert other.macs == model.macs and other.params == model.params
        assert np.array_equal(other(frame), want)


def test_a_sweep_of_an_onnx_detection_task_on_two_workers_equals_one_worker_row_for_row():
    one = fa.sweep(_mission(), payload_kg=[0.0, 0.2], workers=1)
    two = fa.sweep(_mission(), payload_kg=[0.0, 0.2], workers=2)
    assert one["error"].isna().all() and (one["inference_count"] > 0).all()
    assert "map50" in one.columns and one["map50"].notna().all()
    pd.testing.assert_frame_equal(one.reset_index(drop=True), two.reset_index(drop=True))


def test_a_sweep_of_a_replayed_labelled_folder_with_an_onnx_task_on_two_workers(tmp_path):
    """A ReplayCamera (labels, conditions) travels to worker processes too."""
    path, _ = make_set(tmp_path, "yolo-images-labels", n=4)
    d = fa.drone("dji-mavic-2-pro")
    d.add_sensor(fa.sensors.ReplayCamera(path, loop=False, name="eye",
                                         conditions=fa.Conditions(exposure_s=0.005)))
    task = fa.Task(fa.ml.shipped("detector"), sensor="eye", evaluate="detection", name="det",
                   period_s=1.0)
    m = fa.Mission(d, fa.pilots.Hover(10.0, 6.0), tasks=[task])
    one = fa.sweep(m, payload_kg=[0.0, 0.2], workers=1)
    two = fa.sweep(m, payload_kg=[0.0, 0.2], workers=2)
    assert (one["images_scored"] == 4).all() and (one["inference_failures"] == 0).all()
    pd.testing.assert_frame_equal(one.reset_index(drop=True), two.reset_index(drop=True))


def test_a_fleet_with_onnx_detection_tasks_flies_copied_and_pickled_alike():
    """Two drones, each with its own OnnxModel detection task (one remote on the shared
    ground device): a deep copy and a pickled copy (what a worker process receives) fly
    the same KPIs."""
    def drone(name, pad, execution):
        det = fa.ml.OnnxModel(MODELS / "detector.onnx", name="detector")
        task = fa.Task(det, period_s=1.0, evaluate="detection", name="det", execution=execution)
        return fa.FleetDrone(name, fa.drone("dji-mavic-2-pro"), fa.pilots.Hover(20.0, 3.0),
                             pad=pad, tasks=[task], seed=1)
    fleet = fa.Fleet([drone("a", (-10, 0), "onboard"), drone("b", (10, 0), "remote")],
                     world=fa.World.urban(**WORLD), until=12.0)
    k = copy.deepcopy(fleet).run().kpis
    assert k["a.det.inference_count"] > 0 and k["b.det.inference_count"] > 0
    assert k["a.det.compute_energy_j"] > k["b.det.compute_energy_j"]
    assert pickle.loads(pickle.dumps(fleet)).run().kpis == pytest.approx(k, nan_ok=True)
