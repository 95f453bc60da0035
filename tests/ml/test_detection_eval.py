"""Detection and classification scored by the COCO standard (pycocotools),
in flight: a perfect model (the truth itself), a model that drops every
second box, shifted boxes; and the output parsers (N x 6, dicts, YOLO heads)."""

import numpy as np
import pytest

import pytest_flockai as fa
from pytest_flockai.ml import Detections, PythonModel, parse_detections
from pytest_flockai.ml.evaluation import FrameRecord, detection_kpis
from pytest_flockai.world.truth import Objects


def _world():
    return fa.World.urban(seed=11, size=(120.0, 120.0), people=80, crowds=[(10.0, 10.0, 30, 3.0)],
                          vehicles=25, max_building_height=15.0)


def _fly(model_fn, camera, **task_kw):
    d = fa.drone("dji-mavic-2-pro")
    d.add_sensor(camera)
    pilot = fa.pilots.ZigZag(area=((-30, -30), (30, 30)), altitude=25, spacing=30, speed=8)
    task = fa.Task(PythonModel(model_fn, macs=1e8, name="det"), sensor="eye", period_s=1.0,
                   evaluate="detection",
                   **task_kw)
    return fa.Mission(d, pilot, world=_world(), tasks=[task]).run()


def _truth_rows(camera, keep=lambda i: True, shift=0.0):
    o = camera.last_truth.objects
    rows = [[*(b + shift), 0.9, c] for i, (b, c) in enumerate(zip(o.boxes, o.cls)) if keep(i)]
    return np.array(rows, dtype=float).reshape(-1, 6)


def test_a_perfect_model_scores_map50_and_recall_one():
    cam = fa.sensors.Camera(fov_deg=51.0, name="eye")
    r = _fly(lambda frame: _truth_rows(cam), cam, min_visible=0.0)
    k = r.kpis
    assert k["inference_count"] > 20
    assert k["map50"] == pytest.approx(1.0) and k["map50_95"] == pytest.approx(1.0)
    assert k["recall"] == 1.0 and k["precision"] == 1.0
    assert k["recall.person"] == 1.0 and k["recall.vehicle"] == 1.0
    assert k["detection_delay_frames"] == 0.0 and k["objects_missed"] == 0.0
    assert any(n.startswith("recall.alt_20_40m") for n in k)
    assert any(n.startswith("recall.size_") for n in k)


def test_a_model_that_drops_every_second_box_scores_recall_one_half():
    cam = fa.sensors.Camera(fov_deg=51.0, name="eye")
    seen = []                      # (objects in the frame, boxes kept) per inference

    def model(frame):
        rows = _truth_rows(cam, keep=lambda i: i % 2 == 0)
        seen.append((len(cam.last_truth.objects.boxes), len(rows)))
        return rows

    r = _fly(model, cam, min_visible=0.0)
    total, kept = (sum(c) for c in zip(*seen))
    assert 0.5 <= kept / total < 0.56            # odd counts keep one more than half
    assert r.kpis["recall"] == pytest.approx(kept / total, abs=1e-9)
    assert r.kpis["precision"] == 1.0
    assert 0.4 < r.kpis["map50"] < 0.6


def test_boxes_shifted_off_their_objects_score_nothing():
    cam = fa.sensors.Camera(fov_deg=51.0, name="eye")
    r = _fly(lambda frame: _truth_rows(cam, shift=40.0), cam, min_visible=0.0)
    assert r.kpis["recall"] < 0.05 and r.kpis["map50"] < 0.05


def _record(boxes, cls, det_rows, alt=30.0, vis=None, ids=None):
    b = np.array(boxes, float).reshape(-1, 4)
    n = len(b)
    o = Objects(ids=np.arange(n) if ids is None else np.array(ids), cls=np.array(cls, int),
                boxes=b, visible=np.ones(n) if vis is None else np.array(vis, float),
                distance_m=np.full(n, 30.0), gsd_m=np.full(n, 0.1))
    d = np.array(det_rows, float).reshape(-1, 6)
    return FrameRecord(0, o, Detections(d[:, :4], d[:, 4], d[:, 5].astype(int)), alt, 320, 240)


def test_score_threshold_and_hidden_objects():
    boxes = [[10, 10, 20, 30], [100, 100, 140, 120], [200, 50, 210, 70]]
    dets = [[10, 10, 20, 30, 0.9, 0], [100, 100, 140, 120, 0.3, 1], [200, 50, 210, 70, 0.8, 0]]
    rec = _record(boxes, [0, 1, 0], dets, vis=[1.0, 1.0, 0.1])
    k = detection_kpis([rec], ("person", "vehicle"), score_threshold=0.5, min_visible=0.25)
    assert k["recall"] == 0.5               # the hidden person is ignored; the car scored 0.3 < 0.5
    assert k["precision"] == 1.0            # the detection on the hidden person is not a false positive
    assert k["recall.person"] == 1.0 and k["recall.vehicle"] == 0.0
    k2 = detection_kpis([rec], ("person", "vehicle"), score_threshold=0.2, min_visible=0.25)
    assert k2["recall"] == 1.0


def test_detection_delay_counts_frames_to_the_first_hit():
    recs = []
    for i in range(4):                       # object 7 seen in frames 0-3, found from frame 2 on
        det = [[10, 10, 20, 30, 0.9, 0]] if i >= 2 else []
        r = _record([[10, 10, 20, 30]], [0], det, ids=[7])
        r.index = i
        recs.append(r)
    k = detection_kpis(recs, ("person", "vehicle"), score_threshold=0.5, min_visible=0.25)
    assert k["detection_delay_frames"] == 2.0 and k["objects_missed"] == 0.0


def test_parse_n_by_6_pixels_normalised_and_dicts():
    rows = np.array([[10, 20, 30, 40, 0.8, 1]], float)
    d = parse_detections(rows, (240, 320), n_classes=2, where="task 't'")
    np.testing.assert_allclose(d.boxes, [[10, 20, 30, 40]])
    d = parse_detections(rows / [320, 240, 320, 240, 1, 1], (240, 320), n_classes=2, where="t")
    np.testing.assert_allclose(d.boxes, [[10, 20, 30, 40]])
    d = parse_detections({"boxes": [[1, 2, 3, 4]], "scores": [0.5], "labels": [0]}, (240, 320),
                         n_classes=2, where="t", normalized=False)
    assert len(d) == 1 and d.cls[0] == 0


def test_yolov8_and_yolov5_heads_are_decoded_with_nms():
    # two anchors on the same person (overlapping), one vehicle; YOLOv8: (1, 4 + 2, 3)
    v8 = np.array([[[50, 51, 200], [60, 60, 100], [10, 10, 40], [20, 20, 16],
                    [0.9, 0.8, 0.05], [0.1, 0.1, 0.7]]], float)
    d = parse_detections(v8, (240, 320), n_classes=2, where="t", score_threshold=0.25)
    assert len(d) == 2                                    # NMS kept one of the two person boxes
    assert sorted(d.cls.tolist()) == [0, 1]
    np.testing.assert_allclose(d.boxes[d.cls == 0][0], [45, 50, 55, 70])
    v5 = np.array([[[50, 60, 10, 20, 0.9, 1.0, 0.0], [200, 100, 40, 16, 0.8, 0.1, 0.9]]], float)
    d5 = parse_detections(v5, (240, 320), n_classes=2, where="t")
    assert sorted(d5.cls.tolist()) == [0, 1]
    assert d5.scores[d5.cls == 1][0] == pytest.approx(0.72)
    # a model that resized the frame: boxes scaled back to the frame
    d = parse_detections(v8, (480, 640), n_classes=2, where="t", input_hw=(240, 320))
    np.testing.assert_allclose(d.boxes[d.cls == 0][0], [90, 100, 110, 140])


def test_wrong_output_shapes_name_the_task_and_the_shape():
    with pytest.raises(fa.ConfigError, match=r"task 'det': the model returned shape \(3, 5\)"):
        parse_detections(np.zeros((3, 5)), (240, 320), n_classes=2, where="task 'det'")
    with pytest.raises(fa.ConfigError, match="detection class 4 is unknown; allowed: 0..1"):
        parse_detections(np.array([[1, 2, 3, 4, 0.5, 4]]), (240, 320), n_classes=2, where="t")
    with pytest.raises(fa.ConfigError, match="the model returned str"):
        parse_detections("boxes", (240, 320), n_classes=2, where="t")
    with pytest.raises(fa.ConfigError, match="evaluate = 'map' is not allowed"):
        fa.Task(PythonModel(lambda f: 0, macs=1), evaluate="map")


def test_classification_scores_presence_per_class():
    cam = fa.sensors.Camera(fov_deg=51.0, name="eye")

    def present(frame):
        o = cam.last_truth.objects
        return [c for k, c in enumerate(("person", "vehicle")) if (o.cls == k).any()]
    d = fa.drone("dji-mavic-2-pro")
    d.add_sensor(cam)
    task = fa.Task(PythonModel(present, macs=1e7, name="cls"), sensor="eye", period_s=2.0,
                   evaluate="classification", min_visible=0.0)
    pilot = fa.pilots.ZigZag(area=((-30, -30), (30, 30)), altitude=25, spacing=30, speed=8)
    r = fa.Mission(d, pilot, world=_world(), tasks=[task]).run()
    assert r.kpis["accuracy"] == 1.0 and r.kpis["recall.person"] == 1.0
