"""The flight cache beyond single flights: fleets, sweep variants and
the memoised computations (rendered views, conditions applied to them, detection
scores, envelopes). Each part of each key misses when it changes; a cached
value equals the computed one; corrupt entries are recomputed and rewritten."""

import shutil
from pathlib import Path

import numpy as np
import pytest

import pytest_flockai as fa
from pytest_flockai.cache import FlightCache, caching, flight_key, memo_key
from pytest_flockai.cache import key as cache_key
from pytest_flockai.cache.memo_store import MAGIC as MEMO_MAGIC
from pytest_flockai.cache.store import entries
from pytest_flockai.fleet.fleet_result import FleetResult
from pytest_flockai.ml.envelope import envelope
from pytest_flockai.ml.evaluation import FrameRecord, detection_kpis
from pytest_flockai.ml.task_runner import TaskRunner
from pytest_flockai.sweeps import runner

MODELS = Path(__file__).resolve().parents[2] / "fixtures" / "models"
WORLD = fa.World.urban(seed=3, size=(60.0, 60.0), people=30)


# -- fleets ---------------------------------------------------------------------------------------
def fleet(**kw):
    """Two Crazyflies hovering 2 s, 3 m apart (about a second of wall time)."""
    pads = kw.pop("pads", ((0.0, 0.0), (3.0, 0.0)))
    alt = kw.pop("altitude", 1.0)
    seeds = kw.pop("seeds", (0, 1))
    battery = kw.pop("battery_mah", None)
    drones = [fa.FleetDrone(f"d{i}", fa.drone("crazyflie-2-1", **({"battery_mah": battery}
                                                                  if battery and i else {})),
                            fa.pilots.Hover(altitude=alt, duration=2.0), pad=pad, seed=s)
              for i, (pad, s) in enumerate(zip(pads, seeds))]
    return fa.Fleet(drones, world=kw.pop("world", None), **kw)


def test_a_cached_fleet_equals_the_flown_one_and_is_reported_like_a_flight(tmp_path):
    seen = []
    cache = FlightCache(tmp_path)
    with fa.recording(lambda r, m: seen.append(r.cache["status"])), caching(cache):
        flown = fleet(world=WORLD).run()
        again = fleet(world=WORLD).run()
    assert seen == ["stored", "hit"]                   # the sink sees the hit, as for a flight
    assert isinstance(again, FleetResult) and again is not flown
    assert again == flown and again.kpis == flown.kpis
    assert set(again.drones) == {"d0", "d1"}
    assert all(again.drones[n] == flown.drones[n] for n in flown.drones)
    np.testing.assert_array_equal(again.people, flown.people)
    assert len(again.people) == 30
    with caching(None):
        assert fleet(world=WORLD).run() == again       # determinism: flown without the cache


FLEET_CHANGES = {
    "a drone's blueprint value": lambda: fleet(battery_mah=300),
    "the pilot": lambda: fleet(altitude=1.5),
    "a pad": lambda: fleet(pads=((0.0, 0.0), (4.0, 0.0))),
    "a seed": lambda: fleet(seeds=(0, 2)),
    "one drone more": lambda: fleet(pads=((0.0, 0.0), (3.0, 0.0), (6.0, 0.0)), seeds=(0, 1, 2)),
    "until": lambda: fleet(until=1.5),
    "area and swath": lambda: fleet(area=((-5.0, -5.0), (5.0, 5.0)), swath_m=2.0),
    "world": lambda: fleet(world=WORLD),
    "offload period": lambda: fleet(offload=fa.fleet.Offload(period_s=2.0)),
    "offload link": lambda: fleet(offload=fa.fleet.Offload(period_s=1.0, link="sik-915")),
    "offload frame size": lambda: fleet(offload=fa.fleet.Offload(period_s=1.0, frame_bytes=1000)),
}


@pytest.mark.parametrize("part", sorted(FLEET_CHANGES))
def test_each_part_of_a_fleet_changes_its_key(part):
    base = flight_key(fleet(offload=fa.fleet.Offload(period_s=1.0))) if part.startswith(
        "offload") else flight_key(fleet())
    assert flight_key(fleet()) == flight_key(fleet())
    assert flight_key(FLEET_CHANGES[part]()) != base


def test_a_changed_fleet_misses_and_a_package_version_changes_its_key(tmp_path):
    cache = FlightCache(tmp_path)
    with caching(cache):
        fleet().run()
        assert fleet(altitude=1.5).run().cache["status"] == "stored"
    env = cache_key.environment()
    other = {**env, "versions": {**env["versions"], "mujoco": "0.0.1"}}
    assert flight_key(fleet(), other) != flight_key(fleet(), env)


@pytest.mark.parametrize("damage", ["truncated", "tampered"])
def test_a_corrupt_fleet_entry_is_flown_again_and_rewritten(tmp_path, damage):
    cache = FlightCache(tmp_path)
    with caching(cache):
        first = fleet().run()
    (path,) = entries(tmp_path)
    good = path.read_bytes()
    bad = good[:len(good) // 2] if damage == "truncated" else good[:-20] + bytes(
        [good[-20] ^ 1]) + good[-19:]
    path.write_bytes(bad)
    with caching(cache):
        again = fleet().run()
        third = fleet().run()
    assert again.cache["status"] == "replaced" and again == first
    assert third.cache["status"] == "hit" and path.read_bytes() != bad


# -- sweeps ---------------------------------------------------------------------------------------
def _base(alt=1.0):
    return fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=alt, duration=2.0))


@pytest.mark.slow
def test_a_warm_sweep_reads_every_variant_and_starts_no_worker(tmp_path, monkeypatch):
    cache = FlightCache(tmp_path)
    with caching(cache):
        cold = fa.sweep(_base(), payload_kg=[0.0, 0.005], seed=0, workers=2)
    assert cold.attrs["cache"] == {"stored": 2}         # stored by the spawned workers
    assert len(entries(tmp_path)) == 2

    def no_pool(*a, **k):
        raise AssertionError("a warm sweep started a process pool")
    monkeypatch.setattr(runner, "ProcessPoolExecutor", no_pool)
    with caching(cache):
        warm = fa.sweep(_base(), payload_kg=[0.0, 0.005], seed=0, workers=2)
        partly = fa.sweep(_base(), payload_kg=[0.0, 0.01], workers=1)
    assert warm.attrs["cache"] == {"hit": 2}
    cols = [c for c in cold.columns]
    assert warm[cols].equals(cold[cols])
    assert partly.attrs["cache"] == {"hit": 1, "stored": 1}
    with caching(cache):                                 # another base mission: every variant misses
        other = fa.sweep(_base(alt=1.5), payload_kg=[0.0, 0.005], workers=1)
    assert other.attrs["cache"] == {"stored": 2}
    with caching(None):
        assert fa.sweep(_base(), payload_kg=[0.0], workers=1).attrs["cache"] == {}  # no cache


# -- memoised computations --------------------------------------------------------------------------
POSES = [(10.0, 5.0, 20.0, 0.0), (-8.0, 12.0, 20.0, 1.0)]


def views(**kw):
    return fa.sensors.ViewSet(kw.pop("world", WORLD), kw.pop("poses", POSES),
                              kw.pop("camera", {"fov_deg": 60.0}))


def test_rendered_views_and_conditions_come_back_equal(tmp_path):
    plain = views()
    hazy = plain.under(fa.Conditions(visibility_m=200.0, read_noise_e=30.0), velocity=(8.0, 0, 0))
    cache = FlightCache(tmp_path)
    with caching(cache):
        views()
        first = views().under(fa.Conditions(visibility_m=200.0, read_noise_e=30.0), velocity=(8.0, 0, 0))
        cached = views()
        again = cached.under(fa.Conditions(visibility_m=200.0, read_noise_e=30.0), velocity=(8.0, 0, 0))
    assert cache.memo.counts == {"stored": 2, "hit": 3}    # render x3 (1 stored), under x2
    for a, b in zip(cached.frames + [f for f, _ in again], plain.frames + [f for f, _ in hazy]):
        np.testing.assert_array_equal(a, b)
    assert [t.blur_px for _, t in again] == [t.blur_px for _, t in first]


VIEW_CHANGES = {
    "a pose": lambda: views(poses=[(10.0, 5.0, 21.0, 0.0), POSES[1]]),
    "the camera": lambda: views(camera={"fov_deg": 50.0}),
    "the world": lambda: views(world=fa.World.urban(seed=4, size=(60.0, 60.0), people=30)),
}


@pytest.mark.parametrize("part", sorted(VIEW_CHANGES))
def test_each_part_of_a_render_changes_its_key(tmp_path, part):
    cache = FlightCache(tmp_path)
    with caching(cache):
        views()
        VIEW_CHANGES[part]()
    assert cache.memo.counts == {"stored": 2}


UNDER_CHANGES = {
    "conditions": dict(conditions=fa.Conditions(visibility_m=300.0)),
    "velocity": dict(velocity=(4.0, 0.0, 0.0)),
    "seed": dict(seed=1),
}


@pytest.mark.parametrize("part", sorted(UNDER_CHANGES))
def test_each_part_of_conditions_applied_changes_its_key(tmp_path, part):
    vs = views()
    base = dict(conditions=fa.Conditions(visibility_m=200.0, read_noise_e=20.0),
                velocity=(8.0, 0.0, 0.0), seed=0)
    cache = FlightCache(tmp_path)
    with caching(cache):
        vs.under(base["conditions"], velocity=base["velocity"], seed=base["seed"])
        changed = {**base, **UNDER_CHANGES[part]}
        vs.under(changed["conditions"], velocity=changed["velocity"], seed=changed["seed"])
    assert cache.memo.counts == {"stored": 2}


@pytest.fixture(scope="module")
def detector():
    return fa.ml.OnnxModel(MODELS / "detector.onnx", name="detector")


def _records(detector, frames, score=0.05):
    return [FrameRecord(i, t.objects, fa.ml.parse_detections(
        detector(f), f.shape[:2], n_classes=2, where="t", score_threshold=score,
        input_hw=detector.input_size), 20.0, f.shape[1], f.shape[0])
        for i, (f, t) in enumerate(frames)]


def test_detection_scores_are_memoised_on_what_cocoeval_reads(tmp_path, detector):
    recs = _records(detector, views().ideal())
    args = dict(score_threshold=0.4, min_visible=0.25)
    plain = detection_kpis(recs, ("person", "vehicle"), **args)
    fewer = _records(detector, views().ideal(), score=0.1)
    cache = FlightCache(tmp_path)
    with caching(cache):
        detection_kpis(recs, ("person", "vehicle"), **args)
        assert detection_kpis(recs, ("person", "vehicle"), **args) == plain
        assert cache.memo.counts == {"stored": 1, "hit": 1}
        moved = [FrameRecord(r.index, r.truth, fa.ml.Detections(r.detections.boxes + 1.0,
                 r.detections.scores, r.detections.cls), r.altitude_m, r.width, r.height)
                 for r in recs]
        detection_kpis(moved, ("person", "vehicle"), **args)                  # a detection box
        detection_kpis(fewer, ("person", "vehicle"), **args)                  # fewer detections
        detection_kpis(recs, ("person", "vehicle"), score_threshold=0.5, min_visible=0.25)
        detection_kpis(recs, ("person", "vehicle"), score_threshold=0.4, min_visible=0.5)
        detection_kpis(recs, ("vehicle", "person"), **args)                   # the classes
        detection_kpis(recs[:1], ("person", "vehicle"), **args)               # the frames
    assert cache.memo.counts["stored"] == 7
    env = cache_key.environment()
    other = {**env, "versions": {**env["versions"], "pycocotools": "0.0.1"}}
    assert memo_key("detection-kpis", recs, other) != memo_key("detection-kpis", recs, env)


def test_an_envelope_is_memoised_on_the_model_file_bytes_and_every_argument(tmp_path):
    path = tmp_path / "det.onnx"
    shutil.copy(MODELS / "detector.onnx", path)
    model = fa.ml.OnnxModel(path, name="det")
    args = dict(altitudes_m=(20.0,), speeds_mps=(0.0, 8.0), views=2, area=20.0)
    plain = envelope(model, WORLD, **args)
    cache = FlightCache(tmp_path / "cache")
    with caching(cache):
        envelope(model, WORLD, **args)
        before = dict(cache.memo.counts)
        again = envelope(model, WORLD, **args)
        assert cache.memo.counts == {**before, "hit": before.get("hit", 0) + 1}   # one read
        slower = envelope(model, WORLD, **{**args, "speeds_mps": (0.0, 4.0)})
    assert again.equals(plain) and list(again.columns) == list(plain.columns)
    assert list(slower["speed_mps"]) == [0.0, 4.0]            # not the cached (0, 8) envelope
    k = memo_key("envelope", {"model": model, **args})
    data = bytearray(path.read_bytes())
    data[-1] ^= 0xFF                                       # same size, one byte changed
    path.write_bytes(bytes(data))
    assert memo_key("envelope", {"model": model, **args}) != k
    assert memo_key("envelope", {"model": model, **args, "seed": 1}) != memo_key(
        "envelope", {"model": model, **args})


@pytest.mark.parametrize("damage", ["truncated", "tampered", "other format"])
def test_a_corrupt_memo_entry_is_recomputed_and_rewritten(tmp_path, damage):
    cache = FlightCache(tmp_path)
    with caching(cache):
        first = views().frames
    (path,) = sorted((tmp_path / "memo").glob("*/*.memo"))
    good = path.read_bytes()
    assert good.startswith(MEMO_MAGIC)
    if damage == "truncated":
        bad = good[:len(good) // 2]
    elif damage == "tampered":
        bad = good[:-20] + bytes([good[-20] ^ 1]) + good[-19:]
    else:
        bad = b"pytest-flockai-flight-cache/2\n" + good[len(MEMO_MAGIC):]
    path.write_bytes(bad)
    with caching(cache):
        again = views().frames
        third = views().frames
    assert cache.memo.counts == {"stored": 1, "replaced": 1, "hit": 1}
    assert path.read_bytes() == good
    for a, b, c in zip(first, again, third):
        np.testing.assert_array_equal(a, b)
        np.testing.assert_array_equal(a, c)


def test_your_own_model_bypasses_the_memo_unless_marked(tmp_path):
    calls = []

    def model(frame):
        calls.append(1)
        return np.zeros((1, 6))
    cache = FlightCache(tmp_path)
    with caching(cache):
        for _ in range(2):
            envelope(model, WORLD, altitudes_m=(20.0,), speeds_mps=(0.0,), views=1, area=10.0,
                     decode=lambda p, hw: fa.ml.Detections.empty())
    assert cache.memo.counts["bypass"] == 2 and len(calls) == 2   # it saw every frame, twice


def test_memo_modes_follow_the_cache(tmp_path):
    with caching(FlightCache(tmp_path, "read")) as c:
        views()
    assert c.memo.counts == {"computed": 1} and not (tmp_path / "memo").exists()
    with caching(FlightCache(tmp_path, "write")) as c:
        views()
        views()
    assert c.memo.counts == {"stored": 2}
    with caching(FlightCache(tmp_path, "read")) as c:
        views()
    assert c.memo.counts == {"hit": 1}


def test_onnx_inference_is_memoised_on_the_model_bytes_and_the_input(tmp_path):
    path = tmp_path / "det.onnx"
    shutil.copy(MODELS / "detector.onnx", path)
    model = fa.ml.OnnxModel(path, name="det")
    frame = views().frames[0]
    plain = model(frame)
    cache = FlightCache(tmp_path / "cache")
    with caching(cache):
        model(frame)
        again = model(frame)
        other = model(frame[::-1].copy())                  # another input: a miss
    assert cache.memo.counts == {"stored": 2, "hit": 1}
    np.testing.assert_array_equal(again, plain)
    assert not np.array_equal(other, plain)
    x = model.preprocess(frame)
    base = memo_key("onnx-run", {"model": path, "providers": ["CPUExecutionProvider"], "input": x})
    data = bytearray(path.read_bytes())
    data[-1] ^= 0xFF                                       # same size, one byte changed
    path.write_bytes(bytes(data))
    assert memo_key("onnx-run", {"model": path, "providers": ["CPUExecutionProvider"],
                                 "input": x}) != base
    env = cache_key.environment()
    other_env = {**env, "versions": {**env["versions"], "onnxruntime": "0.0.1"}}
    assert memo_key("onnx-run", {"model": path, "input": x}, other_env) != memo_key(
        "onnx-run", {"model": path, "input": x}, env)


def test_a_cached_flight_keeps_the_worlds_people(tmp_path):
    """Regression: a flight read from the cache had no ``people`` (the flight-path
    picture lost them)."""
    def mission():
        return fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=1.0),
                          world=WORLD)
    with caching(FlightCache(tmp_path)):
        flown = mission().run()
        again = mission().run()
    assert again.cache["status"] == "hit"
    assert len(flown.people) == 30
    np.testing.assert_array_equal(again.people, flown.people)


def test_in_flight_the_model_runs_never_a_memoised_answer(tmp_path):
    """A task in flight runs its model (a task with ``latency="measured"`` times it on the
    host; the flight itself is what the cache keeps): with the memo open and the answer
    already stored, neither a measured nor a modeled task reads or writes it."""
    model = fa.ml.OnnxModel(MODELS / "detector.onnx", name="det")
    frame = views().frames[0]
    cache = FlightCache(tmp_path / "cache")
    with caching(cache):
        model(frame)                                       # stored
        for latency in ("measured", "modeled"):
            r = TaskRunner(fa.Task(model, period_s=1.0, latency=latency,
                                   device="raspberry-pi-4")).bind(np.random.default_rng(0))
            pred, err, _ = r._infer(model, frame, r.device)
            assert err is None and pred is not None
    assert cache.memo.counts == {"stored": 1}              # model(frame) outside a task only
