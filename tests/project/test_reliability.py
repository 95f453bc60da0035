"""The core reliability findings, each with a test that failed before the fix:
ONNX external data resolved from the model's folder, invalid predictions
counted as failed inferences, saved flights validated on load, unique
artifact names, the telemetry in chunks, the wall-clock guard and the
resource limits (documented, overridable)."""

import os
import time

import numpy as np
import onnx
import pytest
from onnx import TensorProto, helper, numpy_helper

import pytest_flockai as fa
from pytest_flockai import limits
from pytest_flockai.errors import ConfigError, SimulationError
from pytest_flockai.mission.assemble import Run
from pytest_flockai.mission.plan import resolve
from pytest_flockai.ml import OnnxModel, PythonModel
from pytest_flockai.probes.telemetry import CHUNK_ROWS
from pytest_flockai.reports.files import safe_name as _safe

CF = fa.drone("crazyflie-2-1")


# -- ONNX external data -------------------------------------------------------------------------
def _scale_model(folder, weight: float):
    """y = x * w with w stored as external data in ``weights.bin`` beside the model."""
    w = numpy_helper.from_array(np.array([weight], np.float32), "w")
    g = helper.make_graph([helper.make_node("Mul", ["x", "w"], ["y"])], "scale",
                          [helper.make_tensor_value_info("x", TensorProto.FLOAT, [1, 3, 4, 4])],
                          [helper.make_tensor_value_info("y", TensorProto.FLOAT, [1, 3, 4, 4])], [w])
    m = helper.make_model(g, opset_imports=[helper.make_opsetid("", 13)])
    m.ir_version = 8
    folder.mkdir(parents=True, exist_ok=True)
    onnx.save_model(m, str(folder / "model.onnx"), save_as_external_data=True,
                    all_tensors_to_one_file=True, location="weights.bin", size_threshold=0)
    assert (folder / "weights.bin").is_file()
    return folder / "model.onnx"


def test_onnx_external_data_comes_from_the_models_folder_not_the_working_directory(tmp_path, monkeypatch):
    path = _scale_model(tmp_path / "model", 2.0)
    _scale_model(tmp_path / "cwd", 100.0)            # a weights.bin in the working directory
    monkeypatch.chdir(tmp_path / "cwd")
    model = OnnxModel(path)
    frame = np.full((4, 4, 3), 255, np.uint8)
    assert np.allclose(model(frame), 2.0)            # the model's own weight, not 100
    assert model.params == 1                         # counted from the external initializer


# -- invalid predictions ------------------------------------------------------------------------
@pytest.mark.parametrize("pred", [None, "three", float("nan"), float("inf"), -2.0, {"count": -1}],
                         ids=["none", "string", "nan", "inf", "negative", "dict-negative"])
def test_an_invalid_prediction_is_a_failed_inference_with_the_reason(pred):
    task = fa.Task(PythonModel(lambda f: pred, macs=1000, name="bad"), sensor="gps", period_s=1.0,
                   device="raspberry-pi-4")   # the Crazyflie has no computer of its own
    r = fa.Mission(CF, fa.pilots.Hover(1.0, 3.0), tasks=[task], until=4.0).run()
    k = r.kpis
    assert k["bad.inference_failures"] >= 3 and k["bad.inference_count"] == 0
    errors = [e["error"] for e in r.events if e["kind"] == "inference" and not e.get("ok", True)]
    assert errors and all("invalid prediction" in e for e in errors), errors[:2]
    assert not np.isnan(k["bad.inference_failures"])


@pytest.mark.parametrize("pred", ["boxes", None, float("nan")], ids=["string", "none", "nan"])
def test_an_unparsable_detection_output_is_a_failed_inference_not_a_crash(pred):
    task = fa.Task(PythonModel(lambda f: pred, macs=1000, name="det"), sensor="gps", period_s=1.0,
                   device="raspberry-pi-4",
                   evaluate="detection")
    r = fa.Mission(CF, fa.pilots.Hover(1.0, 2.0), tasks=[task], until=3.0).run()
    assert r.kpis["det.inference_failures"] >= 2 and r.end_reason == "time"
    errors = [e["error"] for e in r.events if e["kind"] == "inference"]
    assert errors and all(e.startswith("invalid prediction") for e in errors), errors[:1]


def test_a_valid_count_is_still_a_successful_inference():
    task = fa.Task(PythonModel(lambda f: 3, macs=1000, name="ok"), sensor="gps", period_s=1.0,
                   device="raspberry-pi-4")   # the Crazyflie has no computer of its own
    r = fa.Mission(CF, fa.pilots.Hover(1.0, 3.0), tasks=[task], until=4.0).run()
    assert r.kpis["ok.inference_failures"] == 0 and r.kpis["ok.inference_count"] >= 3


# -- saved flights -------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def flown():
    return fa.Mission(CF, fa.pilots.Hover(1.0, 0.5), until=2.0).run()


@pytest.mark.parametrize("ext", [".csv", ".jsonl"])
def test_saved_flights_carry_rows_and_checksums_and_load_back_equal(flown, tmp_path, ext):
    p = flown.save(tmp_path / f"f{ext}")
    assert fa.FlightResult.load(p) == flown
    assert sorted(x.name for x in tmp_path.iterdir()) == sorted(
        [p.name] + ([p.name + ".json"] if ext == ".csv" else []))      # no temp files left


def test_a_killed_saves_stale_temp_files_are_removed_a_live_ones_kept(flown, tmp_path):
    stale = tmp_path / ".f.csv.abc123.tmp"
    live = tmp_path / ".f.csv.def456.tmp"
    stale.write_text("half a write")
    live.write_text("being written")
    old = time.time() - 3600
    os.utime(stale, (old, old))
    flown.save(tmp_path / "f.csv")
    assert not stale.exists() and live.exists()


# -- artifact names -------------------------------------------------------------------------------
def test_artifact_names_are_unique_readable_and_never_hidden():
    ids = ["t.py::a/b", "t.py::a_b", "t.py::a:b", "t.py::a b"]
    names = [_safe(i) for i in ids]
    assert len(set(names)) == 4 and all(n.startswith("t.py_a") for n in names)
    long = ["t.py::test[" + "x" * 200 + f"{k}]" for k in range(3)]
    assert len({_safe(i) for i in long}) == 3 and all(len(_safe(i)) <= 131 for i in long)
    for name in ("..", ".", ".hidden", "/", ""):
        assert not _safe(name).startswith(".") and _safe(name) not in ("", "..")
    assert _safe("flight") == "flight" and _safe("flight-2") == "flight-2"


# -- telemetry in chunks, limits, the wall-clock guard ----------------------------------------
def test_telemetry_allocates_one_chunk_up_front_whatever_until_says():
    m = fa.Mission(CF, fa.pilots.Hover(1.0), until=limits.MAX_TIME_S / 6, max_time_s=limits.MAX_TIME_S)
    run = Run(resolve(m), m)
    assert run.telemetry._buf.shape[0] <= CHUNK_ROWS


def test_telemetry_spanning_several_chunks_is_whole_and_in_order():
    r = fa.Mission(CF, fa.pilots.Hover(1.0), until=100.0, telemetry_hz=200.0).run()
    t = r.telemetry.index.to_numpy()
    assert len(t) > 2 * CHUNK_ROWS and np.all(np.diff(t[:-1]) > 0)    # last: the final state
    assert np.median(np.diff(t)) == pytest.approx(1 / 250.0, abs=1e-3)  # every control tick
    assert r.telemetry["battery_remaining"].between(0, 1).all()


def test_the_wall_clock_guard_stops_a_runaway_flight_with_the_partial_result():
    m = fa.Mission(CF, fa.pilots.Hover(1.0), until=3600.0, max_wall_s=0.3)
    t0 = time.perf_counter()
    with pytest.raises(SimulationError, match="max_wall_s = 0.3 s") as info:
        m.run()
    assert time.perf_counter() - t0 < 5.0
    res = info.value.result
    assert res.end_reason == "wall_time" and 0 < res.sim_time_s < 3600
    assert len(res.telemetry) > 0 and res.kpis["energy_total_j"] > 0


def test_limits_are_stated_in_the_error_and_can_be_raised(monkeypatch):
    with pytest.raises(ConfigError, match="limits.MAX_PEOPLE = 3000"):
        fa.World.urban(people=limits.MAX_PEOPLE + 1)
    monkeypatch.setattr(limits, "MAX_PEOPLE", 30_000)
    assert len(fa.World.urban(size=(100, 100), people=10_001, building_density=0.0).people) == 10_001


def test_until_above_max_time_is_refused_not_silently_capped():
    with pytest.raises(ConfigError, match="until = 20000 s is above max_time_s = 14400 s"):
        fa.Mission(CF, fa.pilots.Hover(1.0), until=20000)
    m = fa.Mission(CF, fa.pilots.Hover(1.0), until=20000, max_time_s=20000)
    assert m.until == 20000
