"""Reliability, round 3: label folders read without a
guess, actors and oracles within limits, a call that never returns stopped by
``max_wall_s``, and one clear line for what used to be a raw error."""

import json
import os
import subprocess
import sys
import threading
import time
import tracemalloc
from pathlib import Path

import numpy as np
import pytest
from labelled_sets import make_set

import pytest_flockai as fa
from pytest_flockai import cli, limits
from pytest_flockai.cache import auth
from pytest_flockai.errors import ConfigError, SimulationError
from pytest_flockai.world.actors import ActorSet
from pytest_flockai.world.truth import gimbal_pose, object_truth

ROOT = Path(__file__).resolve().parents[2]
CF = fa.drone("crazyflie-2-1")


def _coco(folder: Path, name="annotations.json") -> dict:
    return json.loads((folder / name).read_text())


def _boxes(cam, k=0) -> int:
    return len(cam._truth[k].objects)


# -- item 5: label folders ---------------------------------------------------------------------
def test_two_coco_files_in_one_folder_need_a_choice(tmp_path):
    folder, _ = make_set(tmp_path, "coco", n=4)
    doc = _coco(folder)
    (folder / "annotations.json").rename(folder / "instances_val.json")
    extra = dict(doc["annotations"][0], id=99, bbox=[0, 0, 8, 8], area=64)
    (folder / "instances_train.json").write_text(json.dumps(
        {**doc, "annotations": doc["annotations"] + [extra]}))
    with pytest.raises(ConfigError, match="instances_train.json, instances_val.json") as e:
        fa.sensors.ReplayCamera(folder)
    assert "split=" in str(e.value)
    assert _boxes(fa.sensors.ReplayCamera(folder, split="val")) == 3
    assert _boxes(fa.sensors.ReplayCamera(folder, split="train")) == 4
    chosen = fa.sensors.ReplayCamera(folder, annotations=str(folder / "instances_train.json"))
    assert _boxes(chosen) == 4


def test_an_image_without_a_coco_entry_is_named(tmp_path):
    folder, _ = make_set(tmp_path, "coco", n=5)
    doc = _coco(folder)
    gone = doc["images"].pop(3)
    doc["annotations"] = [a for a in doc["annotations"] if a["image_id"] != gone["id"]]
    (folder / "annotations.json").write_text(json.dumps(doc))
    with pytest.raises(ConfigError, match="'f03.png' of the folder has no entry in 'images'"):
        fa.sensors.ReplayCamera(folder)


def test_two_coco_entries_for_one_file_are_refused(tmp_path):
    folder, _ = make_set(tmp_path, "coco", n=3)
    doc = _coco(folder)
    doc["images"].append(dict(doc["images"][1], id=77))
    (folder / "annotations.json").write_text(json.dumps(doc))
    with pytest.raises(ConfigError, match=r"images\[3\]: file_name = 'f01.png' is also the "
                                          r"file of images\[1\]"):
        fa.sensors.ReplayCamera(folder)


def test_a_truth_json_that_does_not_cover_the_folder_is_refused(tmp_path):
    folder, _ = make_set(tmp_path, "coco", n=5)
    frame = {"frame": 0, "file": "f00.png", "t": 0.0, "count": 0, "indices": [],
             "pixels": []}
    (folder / "truth.json").write_text(json.dumps({"frames": [frame]}))
    with pytest.raises(ConfigError, match=r"truth.json' has 1 frame\(s\) for the folder's 5"):
        fa.sensors.ReplayCamera(folder)
    frames = [dict(frame, frame=k, file=f"f{(k + 1) % 5:02d}.png") for k in range(5)]
    (folder / "truth.json").write_text(json.dumps({"frames": frames}))
    with pytest.raises(ConfigError, match=r"frames\[0\] file = 'f01.png' is not the folder's"):
        fa.sensors.ReplayCamera(folder)


@pytest.mark.parametrize("kind", ["folder", "fifo", "device"])
def test_a_yolo_label_that_is_not_a_regular_file_is_named(tmp_path, kind):
    folder, _ = make_set(tmp_path, "yolo-flat", n=3)
    label = folder / "f01.txt"
    label.unlink()
    if kind == "folder":
        label.mkdir()
    elif kind == "fifo":
        os.mkfifo(label)
    else:
        os.symlink("/dev/zero", label)
    with pytest.raises(ConfigError, match=r"f01.txt' is not a regular file"):
        fa.sensors.ReplayCamera(folder)


def test_the_same_actor_twice_is_refused():
    walker = fa.actors.Person([(0, 0), (5, 0)])
    with pytest.raises(ConfigError, match=r"actors\[1\] .* is the same object as actors\[0\]"):
        fa.Mission(CF, fa.pilots.Hover(1.0, 1.0), actors=[walker, walker])


def test_two_walkers_at_one_spot_are_both_visible():
    a = fa.actors.Person([(0.0, 0.0), (10.0, 0.0)])
    b = fa.actors.Person([(0.03, 0.0), (10.03, 0.0)])          # 3 cm apart, same way
    _, table = ActorSet([a, b]).table(2.0)
    for view in [((2.8, 0.0, 15.0), 0.0, -90.0),               # above
                 ((-7.2, 0.0, 10.0), 0.0, -45.0),              # behind, along their way
                 ((2.8, -10.0, 10.0), np.pi / 2, -45.0)]:     # from the side
        pos, mat = gimbal_pose(*view)
        objs = object_truth(table, pos, mat, 60.0, 640, 480)
        assert len(objs) == 2 and (objs.visible > 0.5).all(), objs.visible


# -- item 9: limits and hangs ------------------------------------------------------------------
def test_actor_counts_and_oracle_rates_have_limits_checked_first():
    t0 = time.perf_counter()
    with pytest.raises(ConfigError, match="MAX_ACTORS"):
        fa.actors.walkers(20_000, ((0, 0), (100, 100)))
    with pytest.raises(ConfigError, match="MAX_ACTORS"):
        fa.actors.traffic(fa.World.urban(seed=0, size=(100.0, 100.0)), 10**6)
    with pytest.raises(ConfigError, match="false_positives = 1e[+]09.*MAX_ORACLE_FALSE_POSITIVES"):
        fa.ml.Oracle(false_positives=1e9)
    many = [fa.actors.Person([(0, 0)]) for _ in range(limits.MAX_ACTORS + 1)]
    with pytest.raises(ConfigError, match="len\\(actors\\)"):
        fa.Mission(CF, fa.pilots.Hover(1.0, 1.0), actors=many)
    assert time.perf_counter() - t0 < 5.0


def test_the_occlusion_test_scales_to_thousands_of_walkers_in_view():
    acts = fa.actors.walkers(1500, ((-25, -25), (25, 25)), seed=1)
    _, table = ActorSet(acts).table(3.0)
    pos, mat = gimbal_pose((0.0, 0.0, 60.0), 0.0, -90.0)
    tracemalloc.start()
    try:
        t0 = time.perf_counter()
        objs = object_truth(table, pos, mat, 90.0, 1280, 960)
        took = time.perf_counter() - t0
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert len(objs) == 1500
    assert peak < 200 * 2**20, f"{peak / 2**20:.0f} MiB"
    assert took < 10.0


class Stuck(fa.policy.Policy):
    """A policy whose decide never returns after t = 0.5 s (a busy loop that even
    swallows exceptions, or a sleep)."""

    def __init__(self, how):
        super().__init__()
        self.how = how

    def decide(self, t, drone):
        if t < 0.5:
            return
        if self.how == "sleep":
            time.sleep(1e6)
        while True:
            try:
                pass
            except Exception:  # noqa: BLE001 - the overrun must get through this
                pass


def test_a_decide_that_never_returns_is_stopped_by_max_wall_s_in_a_thread():
    out = {}

    def fly():
        try:
            fa.Mission(CF, fa.pilots.Hover(1.0, 5.0), policies=[Stuck("busy")],
                       max_wall_s=2.0).run()
        except SimulationError as exc:
            out["exc"] = exc

    th = threading.Thread(target=fly, daemon=True)
    t0 = time.perf_counter()
    th.start()
    th.join(30.0)
    assert not th.is_alive(), "the flight hangs"
    exc = out["exc"]
    assert exc.end_reason == "wall_time" and "decide" in str(exc)
    assert exc.result.end_reason == "wall_time" and exc.result.kpis["flight_time_s"] > 0
    assert time.perf_counter() - t0 < 10.0


@pytest.mark.slow
def test_a_decide_that_sleeps_for_ever_is_stopped_in_the_main_thread():
    code = ("import time, pytest_flockai as fa\n"
            "from test_reliability_round3 import Stuck, CF\n"
            "t0 = time.perf_counter()\n"
            "try:\n"
            "    fa.Mission(CF, fa.pilots.Hover(1.0, 5.0), policies=[Stuck('sleep')],\n"
            "               max_wall_s=2.0).run()\n"
            "except fa.SimulationError as e:\n"
            "    print(e.end_reason, round(time.perf_counter() - t0, 1), e)\n")
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), str(ROOT / "tests"), str(ROOT / "tests" / "project")]))
    try:
        done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                              timeout=60, env=env)
    except subprocess.TimeoutExpired:
        pytest.fail("the flight hangs")
    assert done.stdout.startswith("wall_time"), done.stdout + done.stderr
    assert "sleep" in done.stdout or "decide" in done.stdout


def test_a_policy_without_decide_is_refused_at_construction():
    class NoDecide(fa.policy.Policy):
        pass

    with pytest.raises(ConfigError, match="NoDecide: a Policy needs a decide"):
        NoDecide()


# -- item 10: messages --------------------------------------------------------------------------
def test_a_yolo_label_that_is_not_utf8_is_named(tmp_path):
    folder, _ = make_set(tmp_path, "yolo-flat", n=3)
    (folder / "f02.txt").write_bytes(b"0 0.5 0.5 0.1 0.1 \xff\xfe\n")
    with pytest.raises(ConfigError, match=r"f02.txt' is not UTF-8"):
        fa.sensors.ReplayCamera(folder)


def test_a_symlinked_key_file_says_so(tmp_path, monkeypatch):
    real = tmp_path / "real-key"
    real.write_text("0123456789abcdef\n")
    os.symlink(real, tmp_path / "key")
    monkeypatch.delenv(auth.ENV_KEY, raising=False)
    monkeypatch.setenv(auth.ENV_KEY_FILE, str(tmp_path / "key"))
    monkeypatch.setattr(auth, "_WARNED", set())
    with pytest.warns(auth.CacheWarning, match="is a symlink"):
        key = auth.default_key()
    assert "symlink" in key.source and key.secret != b"0123456789abcdef"


def test_a_malformed_report_is_one_line_naming_file_and_entry(tmp_path, capsys):
    bad = tmp_path / "r.json"
    bad.write_text(json.dumps({"schema": "pytest-flockai/1",
                               "tests": [{"nodeid": "t::a", "flights": 5}]}))
    assert cli.main(["merge", str(tmp_path / "out.json"), str(bad)]) == cli.USAGE
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert "r.json" in err and "tests[0] ('t::a')" in err and "internal" not in err
    bad.write_text(json.dumps({"schema": "pytest-flockai/1",
                               "tests": [{"nodeid": "t::a", "outcome": "passed",
                                          "flights": [{"kpis": {}}]}]}))
    assert cli.main(["compare", str(bad), str(bad)]) == cli.USAGE
    err = capsys.readouterr().err.strip()
    assert "flights[0]" in err and "name" in err and "KeyError" not in err, err



RAISE_IN_TRACE = '''
import sys, threading, time
from pytest_flockai.mission.watchdog import Overrun, watching

def busy():
    try:
        with watching(time.perf_counter() + 0.2):
            while True:
                pass
    except Overrun:
        pass

th = threading.Thread(target=busy)
th.start()
th.join()

class Stop(Exception):
    pass

def loop():
    n = 0
    for x in (1, 1):
        for y in (1, 1):
            n += x * y
    return n

def tracer(frame, event, arg):
    if frame.f_code is loop.__code__:
        frame.f_trace_opcodes = True
        if event == "opcode" and frame.f_lasti > 20:
            raise Stop
    return tracer

sys.settrace(tracer)
try:
    loop()
except Stop:
    pass
finally:
    sys.settrace(None)
print("done")
'''


def test_a_watchdog_that_fired_leaves_nothing_pending_behind():
    # A pending asynchronous exception dropped with SetAsyncExc(tid, NULL) left CPython's
    # flag raised, and a later traced frame (hypothesis' explain phase, a tracer raising
    # at a backward jump) spun for ever in the same process.
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    try:
        done = subprocess.run([sys.executable, "-c", RAISE_IN_TRACE], capture_output=True,
                              text=True, timeout=60, env=env)
    except subprocess.TimeoutExpired:
        pytest.fail("a traced frame hangs after the watchdog fired")
    assert done.stdout.strip() == "done", done.stdout + done.stderr
