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

Modes: ``"off"``, ``"read"`` (use entries, write none), ``"write"`` (fly every
flight, store it), ``"readwrite"``.
"""

from __future__ import annotations

import shutil
import threading
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from .._io import atomic_write
from ..errors import ConfigError
from ..result import FlightResult
from . import MODES  # the light package module defines them
from . import key as _key
from . import memo as _memo_store
from .entry import MAGIC, CorruptEntry, read_entry, seal, unseal


class CacheWarning(UserWarning):
    """The flight cache could not be written (the run goes on without it)."""


@dataclass
class Lookup:
    """What the cache said about one flight: ``status`` is "hit", "stored",
    "flown" (not stored: read-only mode or the write failed), "bypass" (cannot be
    keyed: ``reason`` says why) or "replaced" (a corrupt entry, flown and rewritten)."""

    status: str
    key: str | None = None
    reason: str | None = None
    result: FlightResult | None = None
    cache: "FlightCache | None" = field(default=None, repr=False)

    def to_dict(self) -> dict:
        return {"status": self.status, "key": self.key, "reason": self.reason}

    def store(self, result: FlightResult) -> None:
        """Store a freshly flown result under this lookup's key (if the mode writes)."""
        if self.cache is not None and self.key is not None:
            self.status = self.cache.put(self.key, result, replaced=self.status == "replaced")
        result.cache = self.to_dict()


class FlightCache:
    """Completed flights under ``directory``, keyed by ``key.flight_key``."""

    def __init__(self, directory, mode: str = "readwrite"):
        if mode not in MODES:
            raise ConfigError(f"flight cache: mode = {mode!r} is not allowed; allowed: "
                              f"{', '.join(MODES)}")
        self.directory = Path(directory)
        self.mode = mode
        self.write_error: str | None = None        # set once a write failed (warned once)
        self._lock = threading.Lock()               # guards write_error only, never a flight
        self._memo = None

    @property
    def reads(self) -> bool:
        return self.mode in ("read", "readwrite")

    @property
    def writes(self) -> bool:
        return self.mode in ("write", "readwrite") and self.write_error is None

    @property
    def memo(self):
        """The memo store beside the flights (``pytest_flockai.cache.memo``)."""
        if self._memo is None:
            self._memo = _memo_store.MemoStore(self)
        return self._memo

    def path(self, key: str) -> Path:
        return self.directory / key[:2] / f"{key}.flight"

    def clear(self) -> None:
        """Remove every entry."""
        shutil.rmtree(self.directory, ignore_errors=True)

    # -- lookups --------------------------------------------------------------------------
    def lookup(self, mission, result_type=FlightResult) -> Lookup:
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
                return Lookup("replaced", key, str(exc), cache=self)
            if res is not None:
                res.cache = {"status": "hit", "key": key, "reason": None}
                return Lookup("hit", key, result=res, cache=self)
        return Lookup("flown", key, cache=self)

    def get(self, key: str, result_type=FlightResult) -> FlightResult | None:
        """The entry of ``key``, None when there is none; CorruptEntry when it is unusable."""
        data = read_entry(self.path(key))
        return None if data is None else decode(data, key, result_type)

    def put(self, key: str, result: FlightResult, *, replaced: bool = False) -> str:
        """Store ``result``; returns the Lookup status ("stored", "replaced" or "flown")."""
        if not self.writes:
            return "replaced" if replaced else "flown"
        try:
            blob = encode(key, result)
            p = self.path(key)
            p.parent.mkdir(parents=True, exist_ok=True)
            atomic_write(p, lambda fh: fh.write(blob), text=False)
        except OSError as exc:
            self.write_failed(exc)
            return "replaced" if replaced else "flown"
        return "replaced" if replaced else "stored"

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
def encode(key: str, result: FlightResult) -> bytes:
    """A flight's entry; a fleet's (a result with ``drones``) holds each drone's too."""
    arrays: dict = {}
    header = _arrays(result, "", arrays)
    drones = getattr(result, "drones", None)
    if drones is not None:
        header["drones"] = [{"name": name, **_arrays(r, f"d{i}_", arrays)}
                            for i, (name, r) in enumerate(drones.items())]
    return seal(key, arrays, header)


def decode(data: bytes, key: str, result_type=FlightResult) -> FlightResult:
    header, arrays = unseal(data, key)
    try:
        out = _result(header, "", arrays, result_type)
        if "drones" in header:
            out.drones = {d["name"]: _result(d, f"d{i}_", arrays, FlightResult)
                          for i, d in enumerate(header["drones"])}
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
    header = {"kpis": r.kpis, "events": r.events, "scenario": r.scenario,
              "energy_breakdown": r.energy_breakdown, "end_reason": r.end_reason,
              "wall_time_s": r.wall_time_s, "probe_errors": r.probe_errors,
              "telemetry": _frame_arrays(r.telemetry, f"{prefix}t_", arrays), "probes": []}
    for j, (name, df) in enumerate(r.probe_samples.items()):
        header["probes"].append({"name": name, **_frame_arrays(df, f"{prefix}p{j}_", arrays)})
    people = getattr(r, "people", None)
    if people is not None:                 # the world's people, drawn on the flight path
        arrays[f"{prefix}people"] = np.asarray(people)
    return header


def _result(h: dict, prefix: str, arrays: dict, result_type) -> FlightResult:
    samples = {p["name"]: _frame(p, f"{prefix}p{j}_", arrays) for j, p in enumerate(h["probes"])}
    out = result_type(h["kpis"], _frame(h["telemetry"], f"{prefix}t_", arrays), h["events"],
                      h["scenario"], h["energy_breakdown"], h["end_reason"], h["wall_time_s"],
                      probe_samples=samples, probe_errors=h["probe_errors"])
    if f"{prefix}people" in arrays:
        out.people = arrays[f"{prefix}people"]
    return out


def entries(directory) -> list[Path]:
    """The entry files under a cache directory."""
    d = Path(directory)
    return sorted(d.glob("*/*.flight")) if d.is_dir() else []


__all__ = ["CacheWarning", "CorruptEntry", "FlightCache", "Lookup", "MAGIC", "MODES", "decode",
           "encode", "entries"]
