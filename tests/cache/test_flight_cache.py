"""The flight cache (pytest_flockai.cache), without pytest in the way: what the
key covers (one test per part), reading back equal results, corrupt entries
never trusted, an unwritable directory that only warns once."""

import hashlib
import json
import shutil
import sys
import types
import warnings
from pathlib import Path

import numpy as np
import pytest

import pytest_flockai as fa
from pytest_flockai.cache import (
    CacheWarning,
    FlightCache,
    Uncacheable,
    cacheable,
    caching,
    flight_key,
)
from pytest_flockai.cache import key as cache_key
from pytest_flockai.cache.store import MAGIC, entries

MODELS = Path(__file__).resolve().parents[2] / "fixtures" / "models"


def hover(**kw):
    """A 2 s Crazyflie hover (well under a second of wall time)."""
    drone = kw.pop("drone", None) or fa.drone("crazyflie-2-1")
    pilot = kw.pop("pilot", None) or fa.pilots.Hover(altitude=1.0, duration=2.0)
    return fa.Mission(drone, pilot, **kw)


# -- a cached result is the flown one ------------------------------------------------------------
def test_a_cached_result_equals_the_flown_one(tmp_path):
    """KPIs, telemetry (dtypes too), events, energy breakdown and probe samples come
    back equal, for a flight with a world, a camera and an ONNX task."""
    model = fa.ml.OnnxModel(MODELS / "crowd_tiny.onnx", name="tiny")
    world = fa.World.urban(seed=3, size=(60.0, 60.0), people=20)

    def mission():
        return fa.Mission(fa.drone("dji-mavic-2-pro"), fa.pilots.Hover(altitude=10.0, duration=6.0),
                          world=world, tasks=[fa.Task(model, period_s=2.0, name="tiny")])
    cache = FlightCache(tmp_path, "readwrite")
    with caching(cache):
        flown = mission().run()
        again = mission().run()
    assert flown.cache["status"] == "stored" and again.cache["status"] == "hit"
    assert again is not flown
    assert again == flown
    assert again.kpis == flown.kpis and again.kpis["inference_count"] > 0
    assert list(again.telemetry.dtypes) == list(flown.telemetry.dtypes)
    assert set(again.probe_samples) == set(flown.probe_samples) and "tiny" in again.probe_samples
    with caching(None):                     # no cache: flown, and equal (determinism)
        plain = mission().run()
    assert plain.cache is None and plain == again


def test_a_cached_detection_flight_keeps_its_worst_frames(tmp_path):
    """The dashboard's ML gallery (a detection task's worst frames, drawn) comes back from
    the cache: a second run of a detection test shows the same gallery as the first."""
    world = fa.World.urban(seed=3, size=(60.0, 60.0), people=30, vehicles=10)

    def mission():
        return fa.Mission(fa.drone("dji-mavic-2-pro"), fa.pilots.Hover(altitude=15.0, duration=3.0),
                          world=world, tasks=[fa.Task(fa.ml.shipped("detector"), period_s=1.0,
                                                      evaluate="detection", name="det")])
    with caching(FlightCache(tmp_path, "readwrite")):
        flown = mission().run()
        again = mission().run()
    assert again.cache["status"] == "hit"
    assert flown.ml_gallery["det"] and flown.ml_gallery["det"][0]["png"]
    assert again.ml_gallery == flown.ml_gallery


def test_modes_read_write_and_off(tmp_path):
    with caching(FlightCache(tmp_path, "read")):
        assert hover().run().cache["status"] == "flown"
    assert entries(tmp_path) == []
    with caching(FlightCache(tmp_path, "write")):
        assert hover().run().cache["status"] == "stored"
        assert hover().run().cache["status"] == "stored"     # write never reads
    with caching(FlightCache(tmp_path, "read")):
        assert hover().run().cache["status"] == "hit"
    with caching(FlightCache(tmp_path, "off")):
        assert hover().run().cache is None
    with pytest.raises(fa.ConfigError, match="mode = 'sometimes'.*readwrite"):
        FlightCache(tmp_path, "sometimes")


# -- the key: one test per part ----------------------------------------------------------------------
@cacheable
def _one(view):
    return {"z": 1.0}


KEY_CHANGES = {
    "blueprint value": lambda: hover(drone=fa.drone("crazyflie-2-1", battery_mah=300)),
    "drone": lambda: hover(drone=fa.drone("dji-mavic-2-pro")),
    "payload": lambda: hover(drone=fa.drone("crazyflie-2-1", payload_kg=0.005)),
    "pilot": lambda: hover(pilot=fa.pilots.Hover(altitude=1.5, duration=2.0)),
    "pilot type": lambda: hover(pilot=fa.pilots.Waypoints([(1.0, 0.0, 1.0)], speed=1.0)),
    "world": lambda: hover(world=fa.World.urban(seed=1, size=(40.0, 40.0), people=5)),
    "seed": lambda: hover(seed=1),
    "until": lambda: hover(until=1.5),
    "wind": lambda: hover(wind=fa.Wind((1.0, 0.0, 0.0))),
    "conditions": lambda: hover(conditions=fa.Conditions(visibility_m=300.0)),
    "telemetry rate": lambda: hover(telemetry_hz=20.0),
    "energy rate": lambda: hover(energy_hz=40.0),
    "return home": lambda: hover(return_home=False),
    "name": lambda: hover(name="other"),
    "probes": lambda: hover(probes=[fa.probes.FunctionProbe("p", _one, [fa.probes.Metric("z")])]),
}


@pytest.mark.parametrize("part", sorted(KEY_CHANGES))
def test_each_part_of_the_scenario_changes_the_key(part):
    base = flight_key(hover())
    assert flight_key(hover()) == base                      # the same scenario, the same key
    assert flight_key(KEY_CHANGES[part]()) != base


def test_a_world_value_changes_the_key():
    a = fa.World.urban(seed=1, size=(40.0, 40.0), people=5)
    b = fa.World.urban(seed=1, size=(40.0, 40.0), people=6)
    c = fa.World.urban(seed=2, size=(40.0, 40.0), people=5)
    keys = {flight_key(hover(world=w)) for w in (a, b, c)}
    assert len(keys) == 3


def test_the_model_file_bytes_change_the_key(tmp_path):
    """Same path, same task: other bytes in the .onnx file, another key."""
    path = tmp_path / "m.onnx"
    shutil.copy(MODELS / "crowd_tiny.onnx", path)
    model = fa.ml.OnnxModel(path, name="m")

    def mission():
        return fa.Mission(fa.drone("dji-mavic-2-pro"), fa.pilots.Hover(altitude=10.0, duration=2.0),
                          tasks=[fa.Task(model, period_s=1.0, name="m")])
    before = flight_key(mission())
    data = bytearray(path.read_bytes())
    data[-1] ^= 0xFF                                        # same size, one byte changed
    path.write_bytes(bytes(data))
    assert flight_key(mission()) != before


def test_task_settings_change_the_key():
    model = fa.ml.OnnxModel(MODELS / "crowd_tiny.onnx", name="m")

    def key(**kw):
        return flight_key(fa.Mission(fa.drone("dji-mavic-2-pro"),
                                     fa.pilots.Hover(altitude=10.0, duration=2.0),
                                     tasks=[fa.Task(model, name="m", **kw)]))
    assert len({key(period_s=1.0), key(period_s=2.0), key(period_s=1.0, device="jetson-orin-nano")}) == 3


def test_the_blueprint_file_bytes_change_the_key(tmp_path):
    """A drone from a blueprint file: an edit to the file is a new key."""
    src = Path(fa.__file__).parent / "airframe" / "blueprints" / "crazyflie-2-1.toml"
    path = tmp_path / "cf.toml"
    path.write_text(src.read_text())
    before = flight_key(hover(drone=fa.drone(path)))
    path.write_text(src.read_text().replace("capacity_mah = 250.0", "capacity_mah = 260.0"))
    edited = flight_key(hover(drone=fa.drone(path)))
    assert edited != before
    path.write_text(src.read_text() + "\n# only a comment\n")   # the file's bytes are keyed too
    assert flight_key(hover(drone=fa.drone(path))) not in (before, edited)


@pytest.mark.parametrize("what", ["pytest-flockai", "mujoco", "onnxruntime",
                                  "opencv-python-headless", "numpy", "pycocotools"])
def test_each_package_version_changes_the_key(what):
    env = cache_key.environment()
    assert env["versions"][what] is not None
    other = {**env, "versions": {**env["versions"], what: env["versions"][what] + ".post1"}}
    assert flight_key(hover(), env) == flight_key(hover())
    assert flight_key(hover(), other) != flight_key(hover(), env)


def test_the_package_source_changes_the_key():
    """An edited checkout (same version number) keys differently."""
    env = cache_key.environment()
    assert env["source"] == cache_key.source_hash() and len(env["source"]) == 64
    assert flight_key(hover(), {**env, "source": "0" * 64}) != flight_key(hover(), env)


def test_the_key_is_stable_across_flights():
    """Flying binds per-flight state onto the drone, the world and sensors; the key
    leaves it out, so the same mission keys the same before and after a flight."""
    world = fa.World.urban(seed=3, size=(60.0, 60.0), people=20)
    model = fa.ml.OnnxModel(MODELS / "crowd_tiny.onnx", name="tiny")
    drone = fa.drone("dji-mavic-2-pro")

    def mission():
        return fa.Mission(drone, fa.pilots.Hover(altitude=10.0, duration=3.0), world=world,
                          tasks=[fa.Task(model, period_s=1.0, name="tiny")])
    before = flight_key(mission())
    mission().run()
    assert flight_key(mission()) == before


def test_your_own_function_bypasses_unless_marked_and_then_its_file_is_keyed(tmp_path,
                                                                           monkeypatch):
    """A PythonModel around your function: flown every time (it may count frames,
    say); marked ``cacheable``, its file's bytes are in the key."""
    mod = tmp_path / "my_counter.py"
    mod.write_text("def count(frame):\n    return 1.0\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    import my_counter

    def mission(fn):
        model = fa.ml.PythonModel(fn, macs=1000, name="c")
        return fa.Mission(fa.drone("dji-mavic-2-pro"), fa.pilots.Hover(altitude=10.0, duration=2.0),
                          tasks=[fa.Task(model, period_s=1.0, name="c")])
    with pytest.raises(Uncacheable, match="is your code.*cacheable"):
        flight_key(mission(my_counter.count))
    cacheable(my_counter.count)
    before = flight_key(mission(my_counter.count))
    assert flight_key(mission(my_counter.count)) == before
    mod.write_text("def count(frame):\n    return 2.0\n")
    assert flight_key(mission(my_counter.count)) != before
    sys.modules.pop("my_counter", None)


def test_a_model_that_counts_its_frames_still_sees_them(tmp_path):
    """The regression this rule prevents: a test that observes its model during the
    flight must see the frames on every run, not a cached result without them."""
    seen = []

    def model(frame):
        seen.append(1)
        return 0.0

    def mission():
        return fa.Mission(fa.drone("dji-mavic-2-pro"), fa.pilots.Hover(altitude=10.0, duration=3.0),
                          tasks=[fa.Task(fa.ml.PythonModel(model, macs=1000), period_s=1.0)])
    with caching(FlightCache(tmp_path)):
        first = mission().run()
        n = len(seen)
        again = mission().run()
    assert n > 0 and len(seen) == 2 * n
    assert first.cache["status"] == again.cache["status"] == "bypass"


# -- what bypasses the cache -----------------------------------------------------------------------------
class Tick(fa.Clocked):
    def step(self, t):
        self.advance_clock()


def test_your_own_components_bypass_the_cache(tmp_path):
    with caching(FlightCache(tmp_path)):
        r = hover(components=[Tick()]).run()
        again = hover(components=[Tick()]).run()
    assert r.cache["status"] == again.cache["status"] == "bypass"
    assert "components of its own (Tick)" in r.cache["reason"]
    assert entries(tmp_path) == []


def test_subscribers_and_unkeyable_objects_bypass_the_cache(tmp_path):
    m = hover()
    m.subscribe(lambda sample: None)
    with pytest.raises(Uncacheable, match="subscribers"):
        flight_key(m)
    ns: dict = {}
    exec("def count(frame):\n    return 0.0\n", ns)          # no file behind it
    model = fa.ml.PythonModel(cacheable(ns["count"]), macs=1000, name="c")
    m = fa.Mission(fa.drone("dji-mavic-2-pro"), fa.pilots.Hover(altitude=10.0, duration=2.0),
                   tasks=[fa.Task(model, period_s=1.0, name="c")])
    with pytest.raises(Uncacheable, match="outside a readable file"):
        flight_key(m)
    with caching(FlightCache(tmp_path)):
        r = m.run()
    assert r.cache["status"] == "bypass" and "readable file" in r.cache["reason"]


# -- corrupt entries: never trusted ------------------------------------------------------------------------
def _stored(tmp_path):
    cache = FlightCache(tmp_path)
    with caching(cache):
        first = hover().run()
    (path,) = entries(tmp_path)
    return cache, first, path


@pytest.mark.parametrize("damage", ["truncated", "tampered", "hash-rewritten", "other key",
                                    "garbage", "empty"])
def test_a_corrupt_entry_is_ignored_and_rewritten(tmp_path, damage):
    cache, first, path = _stored(tmp_path)
    good = path.read_bytes()
    head, _, payload = good[len(MAGIC):].partition(b"\n")
    if damage == "truncated":
        bad = good[:len(good) // 2]
    elif damage == "tampered":                     # one byte of the payload flipped
        bad = bytearray(good)
        bad[-20] ^= 0x01
        bad = bytes(bad)
    elif damage == "hash-rewritten":               # payload changed, meta hash recomputed
        junk = b"PK" + payload[2:-30]
        meta = {"key": first.cache["key"], "size": len(junk),
                "sha256": hashlib.sha256(junk).hexdigest()}
        bad = MAGIC + json.dumps(meta).encode() + b"\n" + junk
    elif damage == "other key":                    # a valid entry filed under another key
        bad = good.replace(first.cache["key"].encode(), b"0" * 64, 1)
    elif damage == "garbage":
        bad = b"\x00\x01 not an entry"
    else:
        bad = b""
    path.write_bytes(bad)
    with caching(cache):
        again = hover().run()
    assert again.cache["status"] == "replaced"
    assert again == first                         # flown again, not read
    assert path.read_bytes() != bad               # and rewritten
    with caching(cache):
        third = hover().run()
    assert third.cache["status"] == "hit" and third == first


def test_an_unwritable_cache_directory_warns_once_and_the_flights_go_on(tmp_path):
    blocker = tmp_path / "a-file"
    blocker.write_text("not a directory")
    cache = FlightCache(blocker / "flights")
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        with caching(cache):
            a = hover().run()
            b = hover(seed=1).run()
    mine = [w for w in seen if issubclass(w.category, CacheWarning)]
    assert len(mine) == 1 and "cannot be written" in str(mine[0].message)
    assert a.cache["status"] == b.cache["status"] == "flown"
    assert a.kpis["flight_time_s"] > 0 and np.isfinite(b.kpis["energy_total_j"])


def test_caching_takes_a_flight_cache_or_none():
    with pytest.raises(fa.ConfigError, match="expected a FlightCache"):
        with caching("yes"):
            pass


def test_a_module_held_by_an_object_is_keyed_by_its_name():
    """A sensor holding a module (cv2) is keyed by the module's name, not by walking it."""
    walked = cache_key._Walker().walk(types, "m")
    assert walked == {"module": "types"}
