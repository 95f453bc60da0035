"""What a detection task got wrong, where a team looks: the worst frames in the HTML
dashboard, loaded in headless Chromium (the gallery is there, and its boxes sit on the
right objects: green on the people the model found, orange on the vehicles it missed,
red where it saw a person on the background), and the task's COCO truth and results
files among the flight's artifacts."""

import base64
import re

import cv2
import numpy as np
import pytest
from labelled_sets import make_set
from pycocotools.coco import COCO
from pycocotools.cocoeval import COCOeval
from test_ci_reports import BROWSER, _browser

from pytest_flockai.ml.gallery import COLOURS, SCALE

BODY = '''
import numpy as np
import pytest_flockai as fa


def blind_to_vehicles(frame):
    """Finds the red people (16 px cells), never the blue vehicles; a person on the
    background at (2, 2)-(10, 10) of every frame."""
    red = (frame[:, :, 0] > 200) & (frame[:, :, 2] < 50)
    rows = [[2, 2, 10, 10, 0.6, 0]]
    for y in range(0, frame.shape[0], 16):
        for x in range(0, frame.shape[1], 16):
            if red[y:y + 16, x:x + 16].all():
                rows.append([x, y, x + 16, y + 16, 0.9, 0])
    return np.array(rows, dtype=float)


def test_detector_on_our_frames():
    d = fa.drone("dji-mavic-2-pro")
    d.add_sensor(fa.sensors.ReplayCamera(PATH, rate_hz=1.0, loop=False, name="eye"))
    task = fa.Task(fa.ml.PythonModel(blind_to_vehicles, macs=1e6), sensor="eye", period_s=1.0,
                   evaluate="detection", name="det")
    r = fa.Mission(d, fa.pilots.Hover(10, 12), tasks=[task]).run()
    assert r.kpis["images_scored"] == 8
'''


def _at(img, x, y):
    return tuple(int(v) for v in img[round(y * SCALE), round(x * SCALE)])


@pytest.mark.skipif(BROWSER is None, reason="no Chromium installed (apt-get install chromium)")
@pytest.mark.browser
def test_the_worst_frames_are_in_the_dashboard_with_boxes_on_the_right_objects(pytester, tmp_path):
    (tmp_path / "set").mkdir()
    path, sc = make_set(tmp_path / "set", "yolo-flat", n=8)
    pytester.makepyfile(test_gallery=BODY.replace("PATH", repr(str(path))))
    out = pytester.path / "dash.html"
    res = pytester.runpytest_inprocess("-p", "no:cacheprovider", "--flockai-html", str(out))
    res.assert_outcomes(passed=1)
    dom = _browser("--dump-dom", out.resolve().as_uri())
    assert dom.returncode == 0, dom.stderr[-2000:]
    figs = re.findall(r'<figure id="pic-\w+" class="ml-frame" data-task="det" data-frame="(\d+)" '
                      r'data-file="(f\d\d\.png)" data-scale="3"><img [^>]*src="data:image/png;'
                      r'base64,([^"]+)"', dom.stdout)
    assert len(figs) == 6                                     # the gallery's six worst frames
    assert "missed" in dom.stdout and "false positive" in dom.stdout
    for _, file, data in figs:
        img = cv2.cvtColor(cv2.imdecode(np.frombuffer(base64.b64decode(data), np.uint8),
                                        cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB)
        boxes, _ = sc[int(file[1:3])]
        assert img.shape[:2] == (128 * SCALE, 160 * SCALE)
        for c, x, y, w, h in boxes:                           # the rectangle's corners
            want = COLOURS["tp"] if c == 0 else COLOURS["miss"]
            assert _at(img, x, y) == want and _at(img, x + w - 0.5, y + h - 0.5) == want
        assert _at(img, 2, 2) == COLOURS["fp"]


def test_artifacts_hold_each_detection_tasks_coco_truth_and_results(pytester, tmp_path):
    """--flockai-artifacts writes <flight>.<task>.truth.json and .results.json; pycocotools
    loads them and scores what the flight reported."""
    (tmp_path / "set").mkdir()
    path, _ = make_set(tmp_path / "set", "yolo-flat", n=8)
    pytester.makepyfile(test_gallery=BODY.replace("PATH", repr(str(path))).replace(
        'assert r.kpis["images_scored"] == 8', 'print("MAP50", r.kpis["map50"])'))
    res = pytester.runpytest_inprocess("-p", "no:cacheprovider", "-s", "--flockai-artifacts",
                                       str(pytester.path / "art"))
    res.assert_outcomes(passed=1)
    (truth,) = (pytester.path / "art").rglob("*.det.truth.json")
    reported = float(re.search(r"MAP50 ([\d.]+)", res.stdout.str()).group(1))
    gt = COCO(str(truth))
    ev = COCOeval(gt, gt.loadRes(str(truth).replace(".truth.json", ".results.json")), "bbox")
    ev.params.maxDets, ev.params.areaRng, ev.params.areaRngLbl = [10, 100, 1000], [[0, 1e10]], ["all"]
    ev.evaluate()
    ev.accumulate()
    ev.summarize()
    assert len(gt.imgs) == 8 and ev.stats[1] == pytest.approx(reported, abs=1e-9)
    assert sorted(im["file_name"] for im in gt.imgs.values()) == [f"f{i:02d}.png" for i in range(8)]
