"""The flight cache on disk: one file per key, written atomically, checked on read.

An entry is ``MAGIC``, one JSON line (the key, the payload's size and SHA-256)
and the payload: a NumPy ``.npz`` (loaded with ``allow_pickle=False``: no code
runs on read) holding the telemetry columns, the probes' samples and the rest
of the FlightResult as JSON. An entry is used only when its key is the one
asked for and the payload's size and hash match; anything else (truncated,
tampered, another format) is a miss: the flight is flown again and the entry
rewritten. Writers never hold a lock: each writes a temporary file and renames
it over the entry, so concurrent pytest-xdist workers (or runs) at worst fly
the same flight twice and write the same bytes.

Entries are sealed with an HMAC keyed by the cache's secret (``auth.py``): an entry
written by someone without the key (a forged one, or one from a CI cache of another
branch with another key) is "replaced", with the reason "not authentic". Reading is
bounded (``entry.py``), and the folder is kept under ``max_bytes`` by evicting the
least recently used entries (``disk.py``).

Modes: ``"off"``, ``"read"`` (use entries, write none), ``"write"`` (fly every
flight, store it), ``"readwrite"``, and ``"verify"``: readwrite, but a sample of
the hits (``verify_fraction``, chosen by key, so the same flights each run) is flown
again and compared with the entry; a mismatch raises ``CacheMismatch``.
"""

from __future__ import annotations

import math
import os
import threading
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from .. import limits
from .._io import atomic_write
from ..errors import ConfigError, FlockAIError
from ..result import FlightResult
from . import auth as _auth
from . import disk as _disk
from . import key as _key
from . import memo_store as _memo_store
from .auth import CacheWarning
from .entry import MAGIC, CorruptEntry, NotAFile, NotAuthentic, read_entry, seal, unseal
from .modes import MODES, VERIFY_FRACTION


class CacheMismatch(FlockAIError):
    """``verify`` flew a cached flight again and got another result: the entry is not
    to be trusted (forged with the key, or the key misses something that shapes it)."""


@dataclass
class Lookup:
    """What the cache said about one flight: ``status`` is "hit", "stored",
    "flown" (not stored: read-only mode or the write failed), "bypass" (cannot be
    keyed: ``reason`` says why), "replaced" (a corrupt or not authentic entry, flown
    and rewritten: ``reason`` says why) or "verified" (a hit flown again, equal)."""

    status: str
    key: str | None = None
    reason: str | None = None
    result: FlightResult | None = None
    cache: FlightCache | None = field(default=None, repr=False)
    cached: FlightResult | None = field(default=None, repr=False)   # verify: the entry

    def to_dict(self) -> dict:
        """What ``FlightResult.cache`` holds: status, key and reason."""
        return {"status": self.status, "key": self.key, "reason": self.reason}

    def store(self, result: FlightResult) -> None:
        """Store a freshly flown result under this lookup's key (if the mode writes);
        ``verify``: compare it with the entry, CacheMismatch when they differ."""
        if self.cached is not None:
            self.status = "verified"
            result.cache = self.to_dict()
            why = mismatch(self.cached, result)
            if why:
                raise CacheMismatch(f"cache entry not authentic: flown again by "
                                    f"--flockai-cache=verify, {why} (entry "
                                    f"{self.cache.path(self.key) if self.cache and self.key else self.key})")
            return
        if self.cache is not None and self.key is not None:
            self.status = self.cache.put(self.key, result, replaced=self.status == "replaced")
        result.cache = self.to_dict()


class FlightCache:
    """Completed flights under ``directory``, keyed by ``key.flight_key``."""

    def __init__(self, directory: str | os.PathLike, mode: str = "readwrite", *,
                 key: bytes | str | _auth.CacheKey | None = None, max_bytes: int | None = None,
                 verify_fraction: float = VERIFY_FRACTION) -> None:
        if mode not in MODES:
            raise ConfigError(f"flight cache: mode = {mode!r} is not allowed; allowed: "
                              f"{', '.join(MODES)}")
        if max_bytes is not None and (isinstance(max_bytes, bool) or
                                      not isinstance(max_bytes, int) or max_bytes < 0):
            raise ConfigError(f"flight cache: max_bytes = {max_bytes!r} is not allowed; "
                              f"expected an integer >= 0 (bytes) or None")
        if isinstance(verify_fraction, bool) or not isinstance(verify_fraction, (int, float)) \
                or not 0 <= verify_fraction <= 1:
            raise ConfigError(f"flight cache: verify_fraction = {verify_fraction!r} is not "
                              f"allowed; expected a number in [0, 1]")
        self.directory = Path(directory)
        self.mode = mode
        self.key = _auth.default_key() if key is None else _auth.from_secret(key)
        self.max_bytes = max_bytes
        self.verify_fraction = float(verify_fraction)
        self._usage: int | None = None              # bytes on disk, as last counted
        self.write_error: str | None = None        # set once a write failed (warned once)
        self._lock = threading.Lock()               # guards write_error only, never a flight
        self._memo: _memo_store.MemoStore | None = None
        self._warned: set[str] = set()              # entries warned about (one warning each)

    @property
    def reads(self) -> bool:
        """Whether this mode reads entries."""
        return self.mode in ("read", "readwrite", "verify")

    @property
    def writes(self) -> bool:
        """Whether this mode writes entries (and no write has failed yet)."""
        return self.mode in ("write", "readwrite", "verify") and self.write_error is None

    @property
    def limit(self) -> int:
        """The folder's size limit in bytes (``limits.MAX_CACHE_BYTES`` unless given)."""
        return limits.MAX_CACHE_BYTES if self.max_bytes is None else self.max_bytes

    def verifies(self, key: str) -> bool:
        """Whether ``verify`` flies this hit again (the same keys every run)."""
        return self.mode == "verify" and int(key[:8], 16) < self.verify_fraction * 2**32

    @property
    def memo(self) -> _memo_store.MemoStore:
        """The memo store beside the flights (``pytest_flockai.cache.memo_store``)."""
        if self._memo is None:
            self._memo = _memo_store.MemoStore(self)
        return self._memo

    def path(self, key: str) -> Path:
        """The file of the entry ``key``."""
        return self.directory / key[:2] / f"{key}.flight"

    def clear(self) -> int:
        """Remove every entry (files carrying the cache's header only: anything else in
        the folder stays); returns how many."""
        with self._lock:
            self._usage = None
            return _disk.clear(self.directory)

    # -- lookups --------------------------------------------------------------------------
    def lookup(self, mission: object, result_type: type[FlightResult] = FlightResult) -> Lookup:
        """The cached result of ``mission`` (a Mission, or a Fleet with ``result_type``
        FleetResult) with status "hit", or a Lookup to store it with."""
        if self.mode == "off":
            return Lookup("off")
        try:
            key = _key.flight_key(mission)
        except _key.Uncacheable as exc:
            return Lookup("bypass", reason=str(exc))
        if self.reads:
            try:
                res = self.get(key, result_type)
            except CorruptEntry as exc:
                if isinstance(exc, NotAFile):
                    self.warn(f"{exc}: treated as a corrupt entry, the flight is flown again",
                              key)
                return Lookup("replaced", key, str(exc), cache=self)
            if res is not None and self.verifies(key):
                return Lookup("verify", key, cache=self, cached=res)
            if res is not None:
                res.cache = {"status": "hit", "key": key, "reason": None}
                return Lookup("hit", key, result=res, cache=self)
        return Lookup("flown", key, cache=self)

    def get(self, key: str,
            result_type: type[FlightResult] = FlightResult) -> FlightResult | None:
        """The entry of ``key``, None when there is none; CorruptEntry when it is unusable
        (``NotAuthentic`` when it was not sealed with this cache's key)."""
        p = self.path(key)
        unsafe = _disk.unsafe_parent(self.directory, p)
        if unsafe:
            raise NotAFile(unsafe)
        data = read_entry(p)
        if data is None:
            return None
        out = decode(data, key, result_type, self.key)
        _disk.touch(p)
        return out

    def put(self, key: str, result: FlightResult, *, replaced: bool = False) -> str:
        """Store ``result``; returns the Lookup status ("stored", "replaced" or "flown")."""
        if not self.writes:
            return "replaced" if replaced else "flown"
        blob = encode(key, result, self.key)
        if not self.write_entry(self.path(key), blob):
            return "replaced" if replaced else "flown"
        self.wrote(len(blob))
        return "replaced" if replaced else "stored"

    def write_entry(self, p: Path, blob: bytes) -> bool:
        """Write an entry's file atomically; False when it was not written: a folder on
        its way is a symlink or not a folder, or something that is not ours sits at its
        path (a warning, this entry only), or the folder cannot be written (a warning,
        no more writes this run)."""
        try:
            unsafe = _disk.unsafe_parent(self.directory, p)
            if unsafe is None:
                p.parent.mkdir(parents=True, exist_ok=True)
                unsafe = _disk.unsafe_parent(self.directory, p)
            if unsafe is None and not _disk.clear_for_write(p):
                unsafe = f"{p} is a folder that is not empty (left as it is)"
            if unsafe is not None:
                self.warn(f"{unsafe}: this entry is not stored", p.stem)
                return False
            atomic_write(p, lambda fh: fh.write(blob), text=False)
        except OSError as exc:
            self.write_failed(exc)
            return False
        return True

    def warn(self, what: str, key: str) -> None:
        """One CacheWarning about one entry (the run goes on): once per entry and cache."""
        with self._lock:
            if key in self._warned:
                return
            self._warned.add(key)
        warnings.warn(f"pytest-flockai: flight cache: {what}", CacheWarning, stacklevel=4)

    def wrote(self, nbytes: int) -> None:
        """Count a written entry; past the limit, evict the least recently used."""
        with self._lock:
            if self._usage is None:
                self._usage = sum(e.size for e in _disk.scan(self.directory))
            else:
                self._usage += nbytes
            if self._usage <= self.limit:
                return
            _disk.prune(self.directory, self.limit)
            self._usage = sum(e.size for e in _disk.scan(self.directory))

    def info(self) -> dict:
        """What ``flockai cache info`` prints: entries, bytes, the limit, the key's source."""
        return {**_disk.info(self.directory), "limit_bytes": self.limit,
                "key_source": self.key.source}

    def prune(self, max_bytes: int | None = None,
              older_than_s: float | None = None) -> tuple[int, int]:
        """Evict down to ``max_bytes`` (default: the limit) and entries unused for
        ``older_than_s``; returns (entries removed, bytes freed)."""
        with self._lock:
            self._usage = None
            return _disk.prune(self.directory, self.limit if max_bytes is None else max_bytes,
                               older_than_s=older_than_s, low_water=1.0)

    def write_failed(self, exc: OSError) -> None:
        """Stop writing for the rest of the run; warn the first time."""
        with self._lock:
            first = self.write_error is None
            self.write_error = f"{self.directory}: {exc.strerror or exc}"
        if first:
            warnings.warn(f"pytest-flockai: the flight cache cannot be written "
                          f"({self.write_error}); flights are flown and not stored for the "
                          f"rest of this run", CacheWarning, stacklevel=3)


# -- the entry format ----------------------------------------------------------------------------
def mismatch(cached: FlightResult, flown: FlightResult) -> str | None:
    """What differs between a cached result and the same flight flown again (KPIs,
    end reason, events), or None."""
    if cached.end_reason != flown.end_reason:
        return f"end reason {cached.end_reason!r} cached, {flown.end_reason!r} flown"
    for name in sorted(set(cached.kpis) | set(flown.kpis)):
        a, b = cached.kpis.get(name), flown.kpis.get(name)
        if not _same(a, b):
            return f"KPI {name} = {a!r} cached, {b!r} flown"
    if len(cached.events) != len(flown.events):
        return f"{len(cached.events)} events cached, {len(flown.events)} flown"
    return None


def _same(a, b) -> bool:
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        return (math.isnan(a) and math.isnan(b)) or math.isclose(a, b, rel_tol=1e-9,
                                                                   abs_tol=1e-12)
    return a == b


def encode(key: str, result: FlightResult, secret: _auth.CacheKey | None = None) -> bytes:
    """A flight's entry; a fleet's (a result with ``drones``) holds each drone's too."""
    arrays: dict = {}
    header = _arrays(result, "", arrays)
    drones = getattr(result, "drones", None)
    if drones is not None:
        header["drones"] = [{"name": name, **_arrays(r, f"d{i}_", arrays)}
                            for i, (name, r) in enumerate(drones.items())]
        header["stations"] = list(getattr(result, "stations", ()))
    return seal(key, arrays, header, secret or _auth.default_key())


def decode(data: bytes, key: str, result_type: type[FlightResult] = FlightResult,
           secret: _auth.CacheKey | None = None) -> FlightResult:
    """The result sealed in an entry (``result_type``: FleetResult for a fleet's,
    with each drone's result in ``drones``); ``NotAuthentic`` or ``ValueError`` when
    it cannot be used."""
    header, arrays = unseal(data, key, secret or _auth.default_key())
    try:
        out: Any = _result(header, "", arrays, result_type)   # a FleetResult with drones
        if "drones" in header:
            out.drones = {d["name"]: _result(d, f"d{i}_", arrays, FlightResult)
                          for i, d in enumerate(header["drones"])}
            out.stations = list(header.get("stations", ()))
        elif result_type is not FlightResult:
            raise ValueError(f"a single flight's entry, not a {result_type.__name__}")
        return out
    except Exception as exc:
        raise CorruptEntry(f"malformed payload ({type(exc).__name__}: {exc})") from None


def _frame_arrays(df: pd.DataFrame, prefix: str, arrays: dict) -> dict:
    cols = []
    arrays[f"{prefix}index"] = df.index.to_numpy()
    for i, c in enumerate(df.columns):
        s = df[c]
        if isinstance(s.dtype, pd.CategoricalDtype):
            arrays[f"{prefix}{i}"] = s.cat.codes.to_numpy()
            cols.append({"name": c, "categories": [str(x) for x in s.cat.categories],
                         "ordered": bool(s.cat.ordered)})
        elif pd.api.types.is_string_dtype(s.dtype) and all(isinstance(x, str) for x in s):
            arrays[f"{prefix}{i}"] = s.to_numpy().astype(str)      # a fleet's "drone" column
            cols.append({"name": c, "text": str(s.dtype)})
        else:
            arrays[f"{prefix}{i}"] = s.to_numpy()
            cols.append({"name": c})
    return {"columns": cols, "index_name": df.index.name}


def _frame(spec: dict, prefix: str, arrays: dict) -> pd.DataFrame:
    data = {}
    for i, col in enumerate(spec["columns"]):
        a = arrays[f"{prefix}{i}"]
        if "categories" in col:
            data[col["name"]] = pd.Categorical.from_codes(
                a, categories=col["categories"], ordered=col["ordered"])
        elif col.get("text"):
            data[col["name"]] = pd.array(a.astype(object), dtype=col["text"])
        else:
            data[col["name"]] = a
    index = pd.Index(arrays[f"{prefix}index"], name=spec["index_name"])
    return pd.DataFrame(data, index=index, columns=[c["name"] for c in spec["columns"]])


def _arrays(r: FlightResult, prefix: str, arrays: dict) -> dict:
    probes: list[dict] = []
    header = {"kpis": r.kpis, "events": r.events, "scenario": r.scenario,
              "energy_breakdown": r.energy_breakdown, "end_reason": r.end_reason,
              "wall_time_s": r.wall_time_s, "probe_errors": r.probe_errors,
              "telemetry": _frame_arrays(r.telemetry, f"{prefix}t_", arrays), "probes": probes}
    for j, (name, df) in enumerate(r.probe_samples.items()):
        probes.append({"name": name, **_frame_arrays(df, f"{prefix}p{j}_", arrays)})
    people = getattr(r, "people", None)
    if people is not None:                 # the world's people, drawn on the flight path
        arrays[f"{prefix}people"] = np.asarray(people)
    gallery = getattr(r, "ml_gallery", None)
    if gallery:                            # the detection tasks' worst frames, for the dashboard
        header["ml_gallery"] = gallery
    return header


def _result(h: dict, prefix: str, arrays: dict, result_type: type[FlightResult]) -> FlightResult:
    samples = {p["name"]: _frame(p, f"{prefix}p{j}_", arrays) for j, p in enumerate(h["probes"])}
    out = result_type(h["kpis"], _frame(h["telemetry"], f"{prefix}t_", arrays), h["events"],
                      h["scenario"], h["energy_breakdown"], h["end_reason"], h["wall_time_s"],
                      probe_samples=samples, probe_errors=h["probe_errors"])
    if f"{prefix}people" in arrays:
        out.people = arrays[f"{prefix}people"]
    if h.get("ml_gallery"):
        out.ml_gallery = h["ml_gallery"]
    return out


def entries(directory: str | os.PathLike) -> list[Path]:
    """The entry files under a cache directory."""
    d = Path(directory)
    return sorted(d.glob("*/*.flight")) if d.is_dir() else []


__all__ = ["CacheMismatch", "CacheWarning", "CorruptEntry", "FlightCache", "Lookup", "MAGIC",
           "MODES", "NotAuthentic", "VERIFY_FRACTION", "decode", "encode", "entries",
           "mismatch"]
