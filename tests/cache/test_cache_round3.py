"""The flight cache, round 3: the key covers every file
a flight reads, a verify fraction needs the verify mode, the cache removes only its own
files, never writes through a symlinked shard folder, and re-flies a folder planted at
an entry's path with one warning."""

import os
import sys
import warnings
from pathlib import Path

import cv2
import numpy as np
import onnx
import pytest
from onnx import numpy_helper

import pytest_flockai as fa
from pytest_flockai import cli
from pytest_flockai.cache import CacheWarning, FlightCache, caching, flight_key
from pytest_flockai.cache.entry import MAGIC
from pytest_flockai.ml import OnnxModel

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from labelled_sets import make_set  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
MEMO_MAGIC = b"pytest-flockai-memo/1\n"
DETECTOR = ROOT / "fixtures" / "models" / "detector.onnx"
CF = fa.drone("crazyflie-2-1")


def mission(**kw):
    return fa.Mission(CF, fa.pilots.Hover(1.0, 0.5), until=1.0, **kw)


# -- item 3: the key covers external weights, replayed images' bytes, side files ------------------
def test_rewriting_an_onnx_models_external_weights_changes_the_key(tmp_path):
    model = onnx.load(DETECTOR)
    onnx.save_model(model, tmp_path / "det.onnx", save_as_external_data=True,
                    all_tensors_to_one_file=True, location="weights.bin", size_threshold=1024)
    weights = tmp_path / "weights.bin"
    assert weights.stat().st_size > 0
    folder, _ = make_set(tmp_path / "set", "coco", n=2)
    key = lambda: flight_key(mission(sensors=[fa.sensors.ReplayCamera(folder)],  # noqa: E731
                                     tasks=[fa.Task(OnnxModel(tmp_path / "det.onnx"),
                                                      execution="remote")]))
    before = key()
    st = weights.stat()
    data = bytearray(weights.read_bytes())
    data[:64] = bytes(64)                              # same size, other weights
    weights.write_bytes(bytes(data))
    os.utime(weights, ns=(st.st_atime_ns, st.st_mtime_ns))   # even with the old mtime
    assert key() != before


def test_the_external_data_locations_of_every_initializer_are_keyed(tmp_path):
    from pytest_flockai.cache.key import _Walker
    w = numpy_helper.from_array(np.ones((4, 4), np.float32), "w")
    b = numpy_helper.from_array(np.ones((4,), np.float32), "b")
    node = onnx.helper.make_node("Gemm", ["x", "w", "b"], ["y"])
    g = onnx.helper.make_graph([node], "g", [onnx.helper.make_tensor_value_info(
        "x", onnx.TensorProto.FLOAT, [1, 4])], [onnx.helper.make_tensor_value_info(
            "y", onnx.TensorProto.FLOAT, [1, 4])], [w, b])
    onnx.save_model(onnx.helper.make_model(g), tmp_path / "m.onnx", save_as_external_data=True,
                    all_tensors_to_one_file=False, size_threshold=0)
    keyed = _Walker().walk(str(tmp_path / "m.onnx"), "m")
    assert sorted(keyed["external"]) == ["b", "w"]


def test_a_replayed_image_rewritten_under_its_old_mtime_changes_the_key(tmp_path):
    folder, _ = make_set(tmp_path, "coco", n=3)
    img = Path(folder) / "f01.png"
    pixels = cv2.imread(str(img), cv2.IMREAD_UNCHANGED)
    stored = [cv2.IMWRITE_PNG_COMPRESSION, 0]   # stored deflate: the size is the pixels'
    img.write_bytes(cv2.imencode(".png", pixels, stored)[1].tobytes())
    cam = lambda: fa.sensors.ReplayCamera(folder, rate_hz=1.0)  # noqa: E731
    before = flight_key(mission(sensors=[cam()]))
    st = img.stat()
    pixels[0, 0] = 255 - pixels[0, 0]
    changed = cv2.imencode(".png", pixels, stored)[1].tobytes()
    assert len(changed) == st.st_size          # same size, same mtime: only the bytes differ
    img.write_bytes(changed)
    os.utime(img, ns=(st.st_atime_ns, st.st_mtime_ns))
    assert flight_key(mission(sensors=[cam()])) != before


def test_side_files_an_object_lists_are_keyed_by_their_bytes(tmp_path):
    from pytest_flockai.cache.key import _Walker
    side = tmp_path / "labels.txt"
    side.write_text("person\n")

    class WithSide:
        side_files = [side]

    first = _Walker().walk(fa.cache.cacheable(WithSide)(), "x")   # instance of a marked class
    side.write_text("car\n")
    assert _Walker().walk(WithSide(), "x") != first


# -- item 4: a verify fraction without the verify mode ---------------------------------------------
@pytest.mark.slow
def test_a_verify_fraction_without_the_verify_mode_is_a_usage_error(pytester):
    pytester.makepyfile("def test_x():\n    pass\n")
    res = pytester.runpytest_subprocess("--flockai-cache-verify=0.5", "-p", "cacheprovider")
    assert res.ret == pytest.ExitCode.USAGE_ERROR
    err = res.stderr.str()
    assert "--flockai-cache-verify" in err and "--flockai-cache=verify" in err, err
    ok = pytester.runpytest_subprocess("--flockai-cache-verify=0.5", "--flockai-cache=verify")
    assert ok.ret == 0


# -- item 6: prune and clear remove only the cache's own files --------------------------------------
def _user_files(d: Path) -> list[Path]:
    files = [d / "db" / "schema.flight", d / "ab" / "notes.memo", d / "memo" / "cd" / "x.memo",
             d / "ab" / "README.txt"]
    for f in files:
        f.parent.mkdir(parents=True, exist_ok=True)
        f.write_text("the user's own file\n")
    return files


def _store_one(d: Path) -> Path:
    c = FlightCache(d, key=b"k")
    with caching(c):
        r = mission().run()
    assert r.cache["status"] == "stored"
    return c.path(r.cache["key"])


def test_prune_all_and_clear_remove_no_user_file(tmp_path, capsys):
    d = tmp_path / "wrong-folder"
    user = _user_files(d)
    entry = _store_one(d)
    assert entry.read_bytes().startswith(MAGIC)
    assert cli.main(["cache", "prune", str(d), "--all"]) == 0
    assert "removed 1 entry" in capsys.readouterr().out
    assert not entry.exists() and all(f.exists() for f in user)
    entry = _store_one(d)
    assert cli.main(["cache", "clear", str(d)]) == 0
    assert not entry.exists() and all(f.exists() for f in user)
    FlightCache(d).clear()
    assert all(f.read_text() == "the user's own file\n" for f in user)
    assert FlightCache(d).info()["entries"] == 0


def test_a_file_with_the_memo_header_is_counted_one_without_is_not(tmp_path):
    from pytest_flockai.cache import disk
    (tmp_path / "memo" / "ef").mkdir(parents=True)
    (tmp_path / "memo" / "ef" / "a.memo").write_bytes(MEMO_MAGIC + b"{}\n")
    (tmp_path / "memo" / "ef" / "b.memo").write_bytes(b"pytest-flockai-memo/0\n")
    assert [e.path.name for e in disk.scan(tmp_path)] == ["a.memo"]


# -- item 7: a symlinked shard folder -----------------------------------------------------------------
def test_a_symlinked_shard_folder_is_never_written_through(tmp_path):
    d, outside = tmp_path / "cache", tmp_path / "outside"
    d.mkdir()
    outside.mkdir()
    key = flight_key(mission())
    os.symlink(outside, d / key[:2])
    with caching(FlightCache(d, key=b"k")), warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        r = mission().run()
    assert ["symlink" in str(w.message) for w in seen
            if issubclass(w.category, CacheWarning)] == [True]          # one warning
    assert r.cache["status"] in ("flown", "replaced")
    assert list(outside.iterdir()) == []
    (outside / f"{key}.flight").write_bytes(b"planted")
    with caching(FlightCache(d, key=b"k")), pytest.warns(CacheWarning, match="symlink"):
        r = mission().run()
    assert r.cache["status"] != "hit"
    assert (outside / f"{key}.flight").read_bytes() == b"planted"
    assert FlightCache(d).info()["entries"] == 0


def test_a_symlinked_memo_folder_is_not_scanned_or_pruned(tmp_path):
    d, outside = tmp_path / "cache", tmp_path / "outside"
    (outside / "ab").mkdir(parents=True)
    victim = outside / "ab" / "v.memo"
    victim.write_bytes(MEMO_MAGIC + b"x")
    d.mkdir()
    os.symlink(outside, d / "memo")
    FlightCache(d).prune(0)
    FlightCache(d).clear()
    assert victim.exists()


# -- item 8: a folder at an entry's path -------------------------------------------------------------
def test_an_empty_folder_at_an_entrys_path_is_reflown_with_one_warning(tmp_path):
    c = FlightCache(tmp_path, key=b"k")
    m = mission()
    c.path(flight_key(m)).mkdir(parents=True)
    with caching(c), warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        r = m.run()
    mine = [w for w in seen if issubclass(w.category, CacheWarning)]
    assert len(mine) == 1 and "folder" in str(mine[0].message), [str(w.message) for w in seen]
    assert r.cache["status"] == "replaced"
    with caching(c):
        assert m.run().cache["status"] == "hit"


def test_a_folder_with_files_at_an_entrys_path_is_left_and_reflown(tmp_path):
    c = FlightCache(tmp_path, key=b"k")
    m = mission()
    p = c.path(flight_key(m))
    p.mkdir(parents=True)
    (p / "mine.txt").write_text("keep")
    for _ in range(2):                    # two runs: each warns once about this entry
        c = FlightCache(tmp_path, key=b"k")
        with caching(c), warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always")
            r = m.run()
        mine = [w for w in seen if issubclass(w.category, CacheWarning)]
        assert len(mine) == 1 and "(a folder)" in str(mine[0].message)
        assert r.cache["status"] in ("replaced", "flown")
    assert (p / "mine.txt").read_text() == "keep"
    assert c.writes                       # the rest of the cache still works
