"""Dataset mode: a labelled folder scored exactly once per image, offline
(``fa.ml.evaluate_dataset``) and in flight (``ReplayCamera(loop=False)``, whose
clock starts at the task's first tick), for COCO, YOLO (flat; images/ + labels/
with a data.yaml) and VisDrone-DET; classes matched by name, not by position."""

import numpy as np
import onnx
import pytest
from labelled_sets import CELL, H, W, make_set, perfect_model
from onnx import TensorProto, helper

import pytest_flockai as fa
from pytest_flockai.ml import PythonModel

LAYOUTS = ["coco", "yolo-flat", "yolo-images-labels", "visdrone"]


def _task(fn, **kw):
    return fa.Task(PythonModel(fn, macs=1e6, name="perfect"), sensor="eye", period_s=1.0,
                   evaluate="detection", name="det", device="jetson-nano-10w", **kw)


@pytest.mark.parametrize("layout", LAYOUTS)
def test_a_perfect_model_scores_one_on_each_of_40_images_offline(tmp_path, layout):
    path, sc = make_set(tmp_path, layout)
    ev = fa.ml.evaluate_dataset(_task(perfect_model(sc, extra=layout == "visdrone")), path)
    k = ev.kpis
    assert k["images_scored"] == 40 and k["inference_failures"] == 0
    assert k["map50"] == pytest.approx(1.0) and k["recall"] == 1.0 and k["precision"] == 1.0
    assert k["recall.person"] == 1.0 and k["recall.vehicle"] == 1.0
    assert sorted(r.file.rsplit("/", 1)[-1] for r in ev.records) == [f"f{i:02d}.png"
                                                                      for i in range(40)]


@pytest.mark.parametrize("layout", LAYOUTS)
def test_a_perfect_model_scores_one_on_each_of_40_images_in_flight(tmp_path, layout):
    path, sc = make_set(tmp_path, layout)
    d = fa.drone("dji-mavic-2-pro")
    d.add_sensor(fa.sensors.ReplayCamera(path, rate_hz=1.0, loop=False, name="eye"))
    task = _task(perfect_model(sc, extra=layout == "visdrone"))
    r = fa.Mission(d, fa.pilots.Hover(10, 50), tasks=[task]).run()
    k = r.kpis
    assert k["images_scored"] == 40 and k["inference_count"] == 40
    assert k["inference_failures"] == 0 and k["frames_dropped"] == 0      # loop=False ends cleanly
    assert k["map50"] == pytest.approx(1.0) and k["recall"] == 1.0 and k["precision"] == 1.0


def test_the_replay_starts_at_the_tasks_first_tick_not_at_take_off(tmp_path):
    path, sc = make_set(tmp_path, "yolo-flat", n=5)
    seen = []

    def model(frame):
        seen.append(int(frame[-1, -1, 0]))
        return perfect_model(sc)(frame)
    d = fa.drone("dji-mavic-2-pro")
    d.add_sensor(fa.sensors.ReplayCamera(path, rate_hz=1.0, loop=False, name="eye"))
    r = fa.Mission(d, fa.pilots.Hover(10, 15), tasks=[_task(model)]).run()
    assert seen == [0, 1, 2, 3, 4]            # every image once, from the first
    assert r.kpis["inference_failures"] == 0 and r.kpis["images_scored"] == 5


def test_reordering_and_renumbering_coco_categories_changes_nothing(tmp_path):
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    _, sc = make_set(tmp_path / "a", "coco", n=12)        # categories [car (1), person (2)]
    make_set(tmp_path / "b", "coco", n=12, categories=[{"id": 7, "name": "person"},
                                                       {"id": 3, "name": "vehicle"}])
    drop = perfect_model(sc, keep=lambda i, k: (i + k) % 3 != 0)
    a = fa.ml.evaluate_dataset(_task(drop), tmp_path / "a").kpis
    b = fa.ml.evaluate_dataset(_task(drop), tmp_path / "b").kpis
    assert 0.5 < a["recall"] < 0.8
    assert a == b


def test_an_alias_is_scored_as_the_tasks_class_and_an_unknown_class_is_refused(tmp_path):
    path, sc = make_set(tmp_path, "coco", n=3)              # categories 'car' and 'person'
    ok = fa.ml.evaluate_dataset(_task(perfect_model(sc)), path).kpis
    assert ok["recall.vehicle"] == 1.0                       # 'car' scored as 'vehicle'
    with pytest.raises(fa.ConfigError, match=r"class 'truck' matches no category.*car, person"):
        fa.ml.evaluate_dataset(_task(perfect_model(sc), classes=("person", "truck")), path)
    with pytest.raises(fa.ConfigError, match="'Person' and 'person' are the same name"):
        fa.ml.evaluate_dataset(_task(perfect_model(sc), classes=("Person", "person")), path)


def _grid_detector(path):
    """A real ONNX detector built with onnx.helper: a 1x1 convolution marks red and
    blue pixels, a 16x16 average pool scores each grid cell, and the cells' boxes are
    constants: a YOLOv8-style head (1, 4 + 2, cells)."""
    n = (H // CELL) * (W // CELL)
    ys, xs = np.divmod(np.arange(n), W // CELL)
    boxes = np.stack([xs * CELL + CELL / 2, ys * CELL + CELL / 2, np.full(n, CELL),
                      np.full(n, CELL)]).astype(np.float32)[None]
    w = np.array([[2, -2, 0], [0, -2, 2]], np.float32).reshape(2, 3, 1, 1)
    init = [helper.make_tensor("w", TensorProto.FLOAT, w.shape, w.ravel()),
            helper.make_tensor("b", TensorProto.FLOAT, [2], [-1.0, -1.0]),
            helper.make_tensor("shape", TensorProto.INT64, [3], [1, 2, n]),
            helper.make_tensor("boxes", TensorProto.FLOAT, boxes.shape, boxes.ravel())]
    nodes = [helper.make_node("Conv", ["images", "w", "b"], ["m"]),
             helper.make_node("Relu", ["m"], ["r"]),
             helper.make_node("AveragePool", ["r"], ["p"], kernel_shape=[CELL, CELL],
                              strides=[CELL, CELL]),
             helper.make_node("Reshape", ["p", "shape"], ["s"]),
             helper.make_node("Concat", ["boxes", "s"], ["out"], axis=1)]
    g = helper.make_graph(nodes, "grid", [helper.make_tensor_value_info(
        "images", TensorProto.FLOAT, [1, 3, H, W])], [helper.make_tensor_value_info(
            "out", TensorProto.FLOAT, [1, 6, n])], init)
    m = helper.make_model(g, opset_imports=[helper.make_opsetid("", 17)])
    m.ir_version = 8
    onnx.save(m, path)
    return path


def test_an_onnx_detector_built_with_onnx_helper_is_perfect_on_a_data_yaml_set(tmp_path):
    path, _ = make_set(tmp_path / "set", "yolo-images-labels")
    model = fa.ml.OnnxModel(_grid_detector(tmp_path / "grid.onnx"), name="grid")
    task = fa.Task(model, sensor="eye", period_s=1.0, evaluate="detection", name="det",
                   decode="yolo", device="jetson-nano-10w")
    off = fa.ml.evaluate_dataset(task, path).kpis
    assert off["images_scored"] == 40 and off["map50"] == pytest.approx(1.0) and off["recall"] == 1.0
    d = fa.drone("dji-mavic-2-pro")
    d.add_sensor(fa.sensors.ReplayCamera(path, rate_hz=1.0, loop=False, name="eye"))
    k = fa.Mission(d, fa.pilots.Hover(10, 50), tasks=[task]).run().kpis
    assert k["images_scored"] == 40 and k["inference_failures"] == 0
    assert k["map50"] == pytest.approx(1.0) and k["recall"] == 1.0


def test_a_model_comparison_puts_accuracy_next_to_latency_energy_and_endurance(tmp_path):
    """The paper's Q4: the grid ONNX detector and a far costlier stand-in on the same frames."""
    path, sc = make_set(tmp_path / "set", "yolo-images-labels", n=10)
    grid = fa.ml.OnnxModel(_grid_detector(tmp_path / "grid.onnx"), name="grid")
    costly = PythonModel(perfect_model(sc, keep=lambda i, k: k != 2), macs=3e9, name="costly")
    hover = fa.Mission(fa.drone("dji-mavic-2-pro"), fa.pilots.Hover(10, 5)).run()
    df = fa.ml.compare_models({"grid": grid, "costly": costly}, path, flight=hover,
                              device="raspberry-pi-4", period_s=1.0, decode="auto")
    g, c = (df.set_index("model").loc[n] for n in ("grid", "costly"))
    assert g["map50"] == pytest.approx(1.0) and g["images_scored"] == c["images_scored"] == 10
    assert c["recall"] == pytest.approx(2 / 3)                 # it never finds the vehicle
    assert g["macs"] < 1e7 < c["macs"] and g["latency_s"] < c["latency_s"]
    assert g["energy_per_inference_j"] < c["energy_per_inference_j"]
    assert hover.kpis["endurance_s"] > g["endurance_s"] > c["endurance_s"]
