"""The flight cache against whoever can write its folder (a CI cache restored from
another branch, a shared runner): entries are authenticated with an HMAC keyed by
FLOCKAI_CACHE_KEY, read without following FIFOs, devices or links, size-checked
before a byte is read or decompressed, and kept under a size limit (LRU)."""

import hashlib
import io
import json
import multiprocessing
import os
import signal
import time
import tracemalloc
import warnings
import zipfile

import numpy as np
import pytest

import pytest_flockai as fa
from pytest_flockai import limits
from pytest_flockai.cache import (
    CacheMismatch,
    FlightCache,
    NotAuthentic,
    caching,
    default_key,
)
from pytest_flockai.cache.entry import CorruptEntry, load_npz, seal, unseal
from pytest_flockai.cache.store import entries

pytest_plugins = ["pytester"]


@pytest.fixture(autouse=True)
def _own_key(monkeypatch, tmp_path):
    """The victim's key; the per-user key file kept out of the real home."""
    monkeypatch.setenv("FLOCKAI_CACHE_KEY", "victim-secret")
    monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / "config"))


@pytest.fixture(autouse=True)
def _no_hang():
    """A read that blocks (a FIFO opened for reading) fails the test instead of hanging."""
    def boom(*_):
        raise TimeoutError("the cache blocked")
    old = signal.signal(signal.SIGALRM, boom)
    signal.alarm(60)
    yield
    signal.alarm(0)
    signal.signal(signal.SIGALRM, old)


def hover(seed=0):
    return fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=2.0),
                      seed=seed)


def _stored(tmp_path):
    cache = FlightCache(tmp_path / "c")
    with caching(cache):
        first = hover().run()
    (path,) = entries(tmp_path / "c")
    return cache, first, path


# -- authenticity ------------------------------------------------------------------------------
def test_a_forged_entry_is_not_trusted_and_the_flight_is_flown_again(tmp_path, monkeypatch):
    """The attack that mattered: re-sealing a doctored result with put()."""
    cache, first, path = _stored(tmp_path)
    key = first.cache["key"]
    forged = hover().run()
    forged.kpis["flight_time_s"] = 1.0
    monkeypatch.delenv("FLOCKAI_CACHE_KEY")        # the attacker does not hold the secret
    attacker = FlightCache(tmp_path / "c")
    assert attacker.key.source != "$FLOCKAI_CACHE_KEY"
    assert attacker.put(key, forged) == "stored"
    monkeypatch.setenv("FLOCKAI_CACHE_KEY", "victim-secret")
    with caching(FlightCache(tmp_path / "c")):
        again = hover().run()
    assert again.cache["status"] == "replaced"
    assert "cache entry not authentic" in again.cache["reason"]
    assert again.kpis["flight_time_s"] == first.kpis["flight_time_s"] > 1.0
    with pytest.raises(NotAuthentic, match="not authentic"):
        FlightCache(tmp_path / "c", key=b"another key").get(key)


def test_an_entry_of_another_key_or_of_none_is_replaced(tmp_path):
    _, first, path = _stored(tmp_path)
    with caching(FlightCache(tmp_path / "c", key="rotated")):
        assert hover().run().cache["status"] == "replaced"
    old = b"pytest-flockai-flight-cache/2\n" + path.read_bytes().split(b"\n", 1)[1]
    path.write_bytes(old)                          # the unkeyed format of before
    with caching(FlightCache(tmp_path / "c")):
        r = hover().run()
    assert r.cache["status"] == "replaced" and r == first


def test_a_hmac_copied_onto_another_payload_fails(tmp_path):
    _, first, path = _stored(tmp_path)
    magic, meta, payload = path.read_bytes().split(b"\n", 2)
    other = FlightCache(tmp_path / "o")
    with caching(other):
        hover(seed=1).run()
    (p2,) = entries(tmp_path / "o")
    _, meta2, payload2 = p2.read_bytes().split(b"\n", 2)
    m = json.loads(meta)
    m.update({k: v for k, v in json.loads(meta2).items() if k in ("size", "sha256")})
    path.write_bytes(magic + b"\n" + json.dumps(m).encode() + b"\n" + payload2)
    with pytest.raises(NotAuthentic):
        FlightCache(tmp_path / "c").get(first.cache["key"])


def test_verify_flies_a_hit_again_and_fails_on_a_mismatch(tmp_path):
    """Someone holding the key (or a key that misses an input) still cannot slip a
    result past --flockai-cache=verify."""
    cache, first, path = _stored(tmp_path)
    doctored = hover().run()
    doctored.kpis["flight_time_s"] = 1.0
    cache.put(first.cache["key"], doctored)        # sealed with the right key
    with caching(FlightCache(tmp_path / "c", "verify", verify_fraction=1.0)):
        with pytest.raises(CacheMismatch, match="cache entry not authentic.*flight_time_s"):
            hover().run()
    cache.put(first.cache["key"], first)
    with caching(FlightCache(tmp_path / "c", "verify", verify_fraction=1.0)):
        assert hover().run().cache["status"] == "verified"
    with caching(FlightCache(tmp_path / "c", "verify", verify_fraction=0.0)):
        assert hover().run().cache["status"] == "hit"


def test_the_per_user_key_is_made_once_private_and_kept(tmp_path, monkeypatch):
    monkeypatch.delenv("FLOCKAI_CACHE_KEY")
    a, b = default_key(), default_key()
    kf = tmp_path / "config" / "pytest-flockai" / "cache-key"
    assert a.secret == b.secret and a.source == str(kf)
    assert kf.stat().st_mode & 0o777 == 0o600
    assert "secret" not in repr(a) and a.secret.decode() not in repr(a)
    with pytest.raises(fa.ConfigError, match="key = b''"):
        FlightCache(tmp_path, key=b"")


# -- hostile files at an entry's path ---------------------------------------------------------------
def _timed_miss(tmp_path, make):
    cache, first, path = _stored(tmp_path)
    path.unlink()
    make(path)
    t0 = time.perf_counter()
    with pytest.raises(CorruptEntry) as info:
        cache.get(first.cache["key"])
    assert time.perf_counter() - t0 < 1.0
    with caching(cache):                            # the run goes on: flown and rewritten
        r = hover().run()
    assert r.cache["status"] == "replaced" and r == first and path.is_file()
    return str(info.value)


def test_a_fifo_is_refused_without_blocking(tmp_path):
    assert "not a regular file" in _timed_miss(tmp_path, os.mkfifo)


def test_a_link_to_dev_zero_is_refused(tmp_path):
    assert "symlink" in _timed_miss(tmp_path, lambda p: os.symlink("/dev/zero", p))


@pytest.mark.skipif(os.geteuid() != 0, reason="mknod needs root")
def test_a_device_node_is_refused(tmp_path):
    assert "not a regular file" in _timed_miss(
        tmp_path, lambda p: os.mknod(p, 0o600 | 0o020000, os.makedev(1, 5)))


def test_an_entry_above_the_size_limit_is_refused_unread(tmp_path, monkeypatch):
    cache, first, path = _stored(tmp_path)
    monkeypatch.setattr(limits, "MAX_CACHE_ENTRY_BYTES", path.stat().st_size - 1)
    with pytest.raises(CorruptEntry, match="MAX_CACHE_ENTRY_BYTES"):
        cache.get(first.cache["key"])


def _bomb(declared: int) -> bytes:
    """An .npz whose one array declares ``declared`` bytes of zeros, really compressed."""
    buf = io.BytesIO()
    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(header, {"descr": "|u1", "fortran_order": False,
                                                  "shape": (declared,)})
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as zf:
        with zf.open("header.npy", "w", force_zip64=True) as fh:
            fh.write(header.getvalue())
            chunk = bytes(2**20)
            for _ in range(declared // len(chunk)):
                fh.write(chunk)
    return buf.getvalue()


def test_a_compressed_bomb_is_refused_before_it_is_unpacked(tmp_path, monkeypatch):
    """Sealed with the right key (defence in depth: an authentic bomb is refused too),
    64 MiB declared against a 1 MiB limit: refused on the declared size, without the
    memory (benchmarks/cache_hostile.py does 2 GiB against the default limit)."""
    monkeypatch.setattr(limits, "MAX_CACHE_UNPACKED_BYTES", 2**20)
    cache = FlightCache(tmp_path)
    payload = _bomb(64 * 2**20)
    blob = seal("k" * 64, {}, {}, cache.key)
    magic, meta, _ = blob.split(b"\n", 2)
    digest = hashlib.sha256(payload).hexdigest()
    m = {"key": "k" * 64, "size": len(payload), "sha256": digest,
         "hmac": cache.key.mac(magic + b"\n", b"k" * 64, digest.encode())}
    data = magic + b"\n" + json.dumps(m).encode() + b"\n" + payload
    tracemalloc.start()
    t0 = time.perf_counter()
    with pytest.raises(CorruptEntry, match="MAX_CACHE_UNPACKED_BYTES"):
        unseal(data, "k" * 64, cache.key)
    took = time.perf_counter() - t0
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert took < 1.0 and peak < 100 * 2**20, (took, peak)


def test_an_array_larger_than_its_bytes_or_of_objects_is_refused(tmp_path):
    cache = FlightCache(tmp_path)
    good = seal("k" * 64, {"a": np.arange(4.0)}, {}, cache.key)
    assert unseal(good, "k" * 64, cache.key)[1]["a"].tolist() == [0.0, 1.0, 2.0, 3.0]
    obj = io.BytesIO()
    with zipfile.ZipFile(obj, "w") as zf:
        b = io.BytesIO()
        np.lib.format.write_array_header_1_0(b, {"descr": "|O", "fortran_order": False,
                                                 "shape": (1,)})
        zf.writestr("x.npy", b.getvalue() + b"\x80\x04N.")
    with pytest.raises(CorruptEntry, match="object arrays"):
        load_npz(obj.getvalue())
    short = io.BytesIO()
    with zipfile.ZipFile(short, "w") as zf:
        b = io.BytesIO()
        np.lib.format.write_array_header_1_0(b, {"descr": "<f8", "fortran_order": False,
                                                 "shape": (2**30,)})
        zf.writestr("x.npy", b.getvalue() + bytes(16))
    with pytest.raises(CorruptEntry, match="does not match"):
        load_npz(short.getvalue())


# -- size limit ------------------------------------------------------------------------------------
def test_the_least_recently_used_entries_are_evicted_past_the_limit(tmp_path):
    cache = FlightCache(tmp_path)
    with caching(cache):
        hover(0).run()
        size = entries(tmp_path)[0].stat().st_size
    small = FlightCache(tmp_path, max_bytes=int(2.5 * size))
    with caching(small):
        hover(1).run()
        time.sleep(0.02)
        assert hover(0).run().cache["status"] == "hit"      # seed 0 used again: now newest
        time.sleep(0.02)
        hover(2).run()                                       # over the limit: seed 1 goes
    with caching(FlightCache(tmp_path, "read")):
        assert [hover(s).run().cache["status"] for s in (0, 1, 2)] == ["hit", "flown", "hit"]
    assert sum(p.stat().st_size for p in entries(tmp_path)) <= 2.5 * size
    with pytest.raises(fa.ConfigError, match="max_bytes = -1"):
        FlightCache(tmp_path, max_bytes=-1)


def test_the_plugin_reports_a_forged_entry_and_keeps_a_failing_test_failing(pytester,
                                                                            monkeypatch):
    """The end-to-end reproduction: a budget that fails must not pass from a forgery."""
    pytester.makepyfile(test_forged='''
import pytest_flockai as fa

def test_quick():
    r = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=2.0)).run()
    assert r.kpis["flight_time_s"] < 1.5, "the budget"
''')
    res = pytester.runpytest("-p", "no:randomly", "--flockai-json=r.json")
    res.assert_outcomes(failed=1)
    folder = pytester.path / ".pytest_cache" / "d" / "flockai-flights"
    (entry,) = entries(folder)
    key = entry.stem
    forged = hover().run()
    forged.kpis["flight_time_s"] = 1.0
    monkeypatch.setenv("FLOCKAI_CACHE_KEY", "the attacker's")
    FlightCache(folder).put(key, forged)
    monkeypatch.setenv("FLOCKAI_CACHE_KEY", "victim-secret")
    res = pytester.runpytest("-p", "no:randomly", "--flockai-json=r.json")
    res.assert_outcomes(failed=1)
    res.stdout.fnmatch_lines(["*untrusted entry replaced (cache entry not authentic*"])


def test_the_plugin_verify_mode_fails_a_test_whose_entry_differs(pytester):
    pytester.makepyfile(test_v='''
import pytest_flockai as fa

def test_quick():
    r = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=2.0)).run()
    assert r.kpis["flight_time_s"] > 1.5
''')
    pytester.runpytest("-p", "no:randomly").assert_outcomes(passed=1)
    folder = pytester.path / ".pytest_cache" / "d" / "flockai-flights"
    (entry,) = entries(folder)
    doctored = hover().run()
    doctored.kpis["flight_time_s"] = 2.5              # sealed with the right key
    FlightCache(folder).put(entry.stem, doctored)
    res = pytester.runpytest("-p", "no:randomly", "--flockai-cache=verify",
                             "--flockai-cache-verify=1")
    res.assert_outcomes(failed=1)
    res.stdout.fnmatch_lines(["*CacheMismatch: cache entry not authentic*flight_time_s*"])
    bad = pytester.runpytest("--flockai-cache-verify=2")
    assert bad.ret == 4 and "--flockai-cache-verify = '2'" in bad.stderr.str()


def _first_key(barrier, out):
    barrier.wait()
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        k = default_key()
    out.put((k.source, hashlib.sha256(k.secret).hexdigest(), [str(w.message) for w in seen]))


def test_processes_that_make_the_key_at_once_all_get_the_one_key(tmp_path, monkeypatch):
    """pytest-xdist's workers on a first run: each reads the key one of them made (a worker
    that read the file before it was written used to seal its entries with a key of its
    own, and the next run flew them again as "not authentic")."""
    monkeypatch.delenv("FLOCKAI_CACHE_KEY")
    ctx = multiprocessing.get_context("fork")
    for round_ in range(6):
        monkeypatch.setenv("XDG_CONFIG_HOME", str(tmp_path / f"config{round_}"))
        n = 8
        barrier, out = ctx.Barrier(n), ctx.Queue()
        procs = [ctx.Process(target=_first_key, args=(barrier, out)) for _ in range(n)]
        for p in procs:
            p.start()
        got = [out.get(timeout=30) for _ in procs]
        for p in procs:
            p.join(timeout=30)
        kf = tmp_path / f"config{round_}" / "pytest-flockai" / "cache-key"
        want = hashlib.sha256(kf.read_bytes().strip()).hexdigest()
        assert got == [(str(kf), want, [])] * n
        assert sorted(os.listdir(kf.parent)) == ["cache-key"]       # no scratch file left
