"""Every malformed label value is a ConfigError naming the file and the entry (never a
raw TypeError, and never silently taken): COCO ids, sizes, iscrowd and visible of the
wrong type; VisDrone-DET and data.yaml mistakes."""

import json

import pytest
from labelled_sets import make_set

import pytest_flockai as fa


def _coco(tmp_path, edit):
    make_set(tmp_path, "coco", n=3)
    p = tmp_path / "annotations.json"
    doc = json.loads(p.read_text())
    edit(doc)
    p.write_text(json.dumps(doc))
    return tmp_path


@pytest.mark.parametrize("edit, message", [
    (lambda d: d["images"][1].update(id=[2]), r"images\[1\]: id = \[2\] is not allowed"),
    (lambda d: d["annotations"][0].update(image_id=[1]), r"annotations\[0\]: image_id = \[1\]"),
    (lambda d: d["annotations"][4].update(category_id={"id": 1}), r"annotations\[4\]: category_id"),
    (lambda d: d["categories"][0].update(id=[1]), r"categories\[0\]: id = \[1\]"),
    (lambda d: d["images"][0].update(width="wide"), r"images\[0\]: width = 'wide' is not allowed"),
    (lambda d: d["images"][2].update(height=0), r"images\[2\]: height = 0 is not allowed"),
    (lambda d: d["annotations"][3].update(visible="yes"), r"annotations\[3\]: visible = 'yes'"),
    (lambda d: d["annotations"][2].update(visible=1.5), r"annotations\[2\]: visible = 1\.5"),
    (lambda d: d["annotations"][1].update(iscrowd="no"), r"annotations\[1\]: iscrowd = 'no' is not"),
    (lambda d: d["annotations"][1].update(iscrowd=2), r"annotations\[1\]: iscrowd = 2 is not"),
    (lambda d: d["annotations"][5].update(bbox="0 0 4 4"), r"annotations\[5\]: bbox = '0 0 4 4'"),
    (lambda d: d["annotations"][5].update(bbox=[1, 2, True, 4]), r"annotations\[5\]: bbox"),
    (lambda d: d["annotations"][6].update(id=d["annotations"][0]["id"]),
     r"annotations\[6\]: id = 1000 is used by another annotation"),
    (lambda d: d["images"].append(dict(d["images"][0])), r"images\[3\]: id = 1 is used by another"),
    (lambda d: d["categories"][1].update(name=None), r"categories\[1\]: name = None"),
    (lambda d: d["images"][0].update(file_name=7), r"images\[0\]: file_name = 7 is not a string"),
])
def test_a_malformed_coco_value_names_the_file_and_the_entry(tmp_path, edit, message):
    folder = _coco(tmp_path, edit)
    for read in (lambda: fa.sensors.ReplayCamera(folder),
                 lambda: fa.ml.evaluate_dataset(fa.Task(lambda f: f, evaluate="detection",
                                                        latency="measured"), folder)):
        with pytest.raises(fa.ConfigError, match=message) as exc:
            read()
        assert "annotations.json" in str(exc.value)


@pytest.mark.parametrize("line, message", [
    ("1,2,3", r"f00\.txt'?: line 1 = '1,2,3' is not 'x,y,w,h,score,category"),
    ("1,2,3,4,1,12,0,0", r"line 1: category 12 is unknown; VisDrone-DET categories 0\.\.11"),
    ("1,2,3,4,1,1,0,5", r"line 1: score = 1, occlusion = 5 is not allowed"),
    ("1,2,0,4,1,1,0,0", r"line 1: box 1,2,0,4 needs a width and a height > 0"),
    ("150,2,30,4,1,1,0,0", r"line 1: box \(150, 2, 180, 6\) lies outside the 160x128 image"),
    ("a,2,3,4,1,1,0,0", r"line 1 = 'a,2,3,4,1,1,0,0' is not"),
])
def test_a_malformed_visdrone_line_names_the_file_and_the_line(tmp_path, line, message):
    make_set(tmp_path, "visdrone", n=2)
    (tmp_path / "annotations" / "f00.txt").write_text(line + "\n")
    with pytest.raises(fa.ConfigError, match=message):
        fa.sensors.ReplayCamera(tmp_path)


def test_data_yaml_mistakes_name_the_file_and_the_key(tmp_path):
    path, _ = make_set(tmp_path, "yolo-images-labels", n=2)
    with pytest.raises(fa.ConfigError, match=r"split = 'test' is not in .*data\.yaml.*'val', 'train'"):
        fa.sensors.ReplayCamera(path, split="test")
    path.write_text("path: .\nval: images/nowhere\nnames: [a, b]\n")
    with pytest.raises(fa.ConfigError, match=r"val: 'images/nowhere' is not a folder"):
        fa.sensors.ReplayCamera(path)
    path.write_text("path: .\nval: images/val\nnames:\n  0: car\n  2: pedestrian\n")
    with pytest.raises(fa.ConfigError, match=r"names: indices \[0, 2\] are not 0\.\.1"):
        fa.sensors.ReplayCamera(path)
    path.write_text("path: .\nval: images/val\nnames: [car]\n")
    with pytest.raises(fa.ConfigError, match=r"val[/\\]f00\.txt'?: line 1: class 1 is unknown"):
        fa.sensors.ReplayCamera(path)
    (tmp_path / "labels" / "val" / "ghost.txt").write_text("0 0.5 0.5 0.1 0.1\n")
    with pytest.raises(fa.ConfigError, match=r"label file 'ghost\.txt' has no image"):
        fa.sensors.ReplayCamera(path)


def test_classes_for_labels_that_name_their_own_categories_are_refused(tmp_path):
    make_set(tmp_path, "coco", n=2)
    with pytest.raises(fa.ConfigError, match=r"classes = \['person', 'vehicle'\] names YOLO class"):
        fa.sensors.ReplayCamera(tmp_path, classes=["person", "vehicle"])


def test_a_missing_or_empty_folder_names_evaluate_dataset_and_the_path(tmp_path):
    task = fa.Task(lambda f: f, evaluate="detection", latency="measured", name="det")
    with pytest.raises(fa.ConfigError, match=r"^evaluate_dataset\(task 'det'\): .*path = '.*nowhere'"
                                             r": no such folder"):
        fa.ml.evaluate_dataset(task, tmp_path / "nowhere")
    with pytest.raises(fa.ConfigError, match=r"^evaluate_dataset\(task 'det'\): .*holds no images"):
        fa.ml.evaluate_dataset(task, tmp_path)


def test_a_model_that_fails_on_every_image_is_a_config_error_naming_why(tmp_path):
    """decode='boxes' on a model that returns a YOLO head: not map50 0.0 and a count of
    failures, but the first failure's reason."""
    import numpy as np

    make_set(tmp_path, "coco", n=3)
    yolo_head = fa.ml.PythonModel(lambda f: np.zeros((1, 6, 80), np.float32), macs=1e6)
    task = fa.Task(yolo_head, evaluate="detection", decode="boxes", name="det")
    with pytest.raises(fa.ConfigError, match=r"^evaluate_dataset\(task 'det'\): the model failed on "
                                             r"every one of the 3 image\(s\); the first, .*shape"):
        fa.ml.evaluate_dataset(task, tmp_path)
