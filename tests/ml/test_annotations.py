"""Bring your own data: a folder of frames with COCO or YOLO labels replayed in
flight timing and scored against its labels; bad annotation files give clear
errors naming the file and the entry."""

import json

import cv2
import numpy as np
import pytest

import pytest_flockai as fa
from pytest_flockai.ml import PythonModel

RED, BLUE = (220, 30, 30), (30, 60, 220)


def _make_set(folder, n=6, seed=0):
    """Frames with red squares (people) and blue bars (vehicles) at known places."""
    rng = np.random.default_rng(seed)
    labels = []
    for i in range(n):
        img = np.full((120, 160, 3), 90, np.uint8)
        objs = []
        for k in range(3):
            x, y = int(rng.integers(5, 120)), int(rng.integers(5, 90))
            w, h, c = (6, 6, 0) if k < 2 else (30, 12, 1)
            cv2.rectangle(img, (x, y), (x + w - 1, y + h - 1), RED if c == 0 else BLUE, -1)
            objs.append((c, x, y, w, h))
        cv2.imwrite(str(folder / f"f{i:02d}.png"), cv2.cvtColor(img, cv2.COLOR_RGB2BGR))
        labels.append(objs)
    return labels


def _write_coco(folder, labels, size=(160, 120)):
    images = [{"id": i + 1, "file_name": f"f{i:02d}.png", "width": size[0], "height": size[1]}
              for i in range(len(labels))]
    anns = [{"id": len(images) * 10 + i * 3 + k, "image_id": i + 1, "category_id": c + 1,
             "bbox": [x, y, w, h], "area": w * h, "iscrowd": 0}
            for i, objs in enumerate(labels) for k, (c, x, y, w, h) in enumerate(objs)]
    doc = {"images": images, "annotations": anns,
           "categories": [{"id": 1, "name": "person"}, {"id": 2, "name": "vehicle"}]}
    (folder / "annotations.json").write_text(json.dumps(doc))
    return doc


def _write_yolo(folder, labels, names=("person", "vehicle")):
    (folder / "classes.txt").write_text("\n".join(names) + "\n")
    for i, objs in enumerate(labels):
        (folder / f"f{i:02d}.txt").write_text("".join(
            f"{c} {(x + w / 2) / 160} {(y + h / 2) / 120} {w / 160} {h / 120}\n"
            for c, x, y, w, h in objs))


def colour_detector(frame):
    """A real (tiny) detector: OpenCV colour thresholds and contours."""
    out = []
    for c, rgb in ((0, RED), (1, BLUE)):
        mask = (np.abs(frame.astype(int) - rgb).sum(axis=2) < 60).astype(np.uint8)
        n, _, stats, _ = cv2.connectedComponentsWithStats(mask)
        for x, y, w, h, _ in stats[1:]:
            out.append([x, y, x + w, y + h, 0.9, c])
    return np.array(out, float).reshape(-1, 6)


@pytest.mark.parametrize("fmt", ["coco", "yolo"])
def test_a_teams_own_frames_are_scored_against_their_labels_in_flight(tmp_path, fmt):
    labels = _make_set(tmp_path)
    (_write_coco if fmt == "coco" else _write_yolo)(tmp_path, labels)
    cam = fa.sensors.ReplayCamera(tmp_path, rate_hz=1.0, name="eye")
    assert cam._truth[0].objects.boxes.shape == (3, 4)
    d = fa.drone("dji-mavic-2-pro")
    d.add_sensor(cam)
    task = fa.Task(PythonModel(colour_detector, macs=2e6, name="colours"), sensor="eye",
                   period_s=1.0, evaluate="detection", device="jetson-nano-10w")
    r = fa.Mission(d, fa.pilots.Hover(10, 12), tasks=[task]).run()
    assert r.kpis["inference_count"] >= 10
    assert r.kpis["map50"] == pytest.approx(1.0) and r.kpis["recall"] == 1.0
    assert r.kpis["inference_latency_p50_s"] < 0.1                 # flight timing on the Jetson


def test_replayed_labels_count_people_for_counting_tasks(tmp_path):
    labels = _make_set(tmp_path, n=2)
    _write_coco(tmp_path, labels)
    cam = fa.sensors.ReplayCamera(tmp_path)
    cam.bind(None, None, np.random.default_rng(0))
    cam.read(0.0)
    assert cam.last_truth.count == 2                  # the two 'person' boxes


def _bad(tmp_path, doc_edit=None, text=None):
    labels = _make_set(tmp_path, n=2)
    doc = _write_coco(tmp_path, labels)
    if doc_edit:
        doc_edit(doc)
        (tmp_path / "annotations.json").write_text(json.dumps(doc))
    if text is not None:
        (tmp_path / "annotations.json").write_text(text)
    return tmp_path


@pytest.mark.parametrize("edit, text, message", [
    (None, "{not json", r"annotations\.json'?: not a readable JSON file"),
    (lambda d: d.pop("categories"), None, r"missing list 'categories'"),
    (lambda d: d["annotations"][1].pop("bbox"), None, r"annotations\[1\] .*needs 'image_id', 'category_id' and 'bbox'"),
    (lambda d: d["annotations"][0].update(bbox=[150, 100, 30, 30]), None,
     r"annotations\[0\]: box \(150, 100, 180, 130\) lies outside the 160x120 image"),
    (lambda d: d["annotations"][2].update(category_id=9), None,
     r"annotations\[2\]: category_id = 9 is not in 'categories'"),
    (lambda d: d["images"][0].update(width=640), None,
     r"images\[0\]: size 640x120 differs from the image file's 160x120"),
    (lambda d: d["images"][1].update(file_name="missing.png"), None,
     r"images\[1\]: file_name = 'missing.png' is not an image of the folder"),
    (lambda d: d["annotations"][0].update(bbox=[1, 2, 0, 5]), None,
     r"annotations\[0\]: bbox = \[1, 2, 0, 5\] is not allowed"),
])
def test_malformed_coco_files_name_the_file_and_the_entry(tmp_path, edit, text, message):
    folder = _bad(tmp_path, edit, text)
    with pytest.raises(fa.ConfigError, match=message) as exc:
        fa.sensors.ReplayCamera(folder)
    assert "annotations.json" in str(exc.value)


@pytest.mark.parametrize("line, message", [
    ("5 0.5 0.5 0.1 0.1", r"f00\.txt'?: line 1: class 5 is unknown; classes 0\.\.1: person, vehicle"),
    ("0 0.5 0.5", r"line 1 = '0 0\.5 0\.5' is not 'class cx cy w h'"),
    ("0 0.5 0.5 1.5 0.1", r"box 0\.5 0\.5 1\.5 0\.1 is not normalised"),
    ("0 0.98 0.5 0.2 0.1", r"lies outside the 160x120 image"),
])
def test_malformed_yolo_labels_name_the_file_and_the_line(tmp_path, line, message):
    labels = _make_set(tmp_path, n=2)
    _write_yolo(tmp_path, labels)
    (tmp_path / "f00.txt").write_text(line + "\n")
    with pytest.raises(fa.ConfigError, match=message):
        fa.sensors.ReplayCamera(tmp_path)


def test_yolo_labels_without_images_or_class_names_are_refused(tmp_path):
    labels = _make_set(tmp_path, n=2)
    _write_yolo(tmp_path, labels)
    (tmp_path / "ghost.txt").write_text("0 0.5 0.5 0.1 0.1\n")
    with pytest.raises(fa.ConfigError, match=r"label file 'ghost\.txt' has no image"):
        fa.sensors.ReplayCamera(tmp_path)
    (tmp_path / "ghost.txt").unlink()
    (tmp_path / "classes.txt").unlink()
    with pytest.raises(fa.ConfigError, match="need class names"):
        fa.sensors.ReplayCamera(tmp_path)
    cam = fa.sensors.ReplayCamera(tmp_path, classes=["person", "vehicle"])
    assert cam._truth[1].objects.classes == ("person", "vehicle")
