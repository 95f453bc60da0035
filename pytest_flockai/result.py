"""FlightResult: what a flown mission hands back, and how it is saved.

``save(path)`` writes the telemetry as CSV (``.csv``) or Parquet
(``.parquet``, needs the optional ``pyarrow``) plus a JSON sidecar
(``<path>.json``) with the scenario, KPIs, events, energy breakdown and the
probes' own samples; ``.jsonl`` writes JSON lines (a header line, then one
line per telemetry row) for streaming tools. ``FlightResult.load(path)``
reads any of them back; a reloaded result compares equal to the saved one.
Files are written atomically (temporary file, then rename); the header holds
the telemetry's row count and SHA-256 and its own SHA-256, checked on load.
"""

from __future__ import annotations

import glob
import hashlib
import json
import math
import os
import re
import time
from collections.abc import Mapping
from pathlib import Path
from types import MappingProxyType

import numpy as np
import pandas as pd

from . import notebook as _notebook
from ._io import atomic_write, sha256_of
from .errors import ConfigError, WriteError
from .phases import PHASES, STAGES

# The default C parser of pandas before 3.1 (2.1 and 3.0 measured) is off by an ulp on some
# values, so those read with float_precision="round_trip"; 3.1 parses exactly by default and
# deprecates the argument (Pandas4Warning).
_PANDAS = tuple(int(x) for x in re.findall(r"\d+", pd.__version__)[:2])
_CSV_FLOATS = {"float_precision": "round_trip"} if _PANDAS < (3, 1) else {}

FORMAT = "pytest-flockai-flight/1"
#: s: a temporary file of a save left untouched this long was left by a killed process
STALE_TEMP_S = 300.0
#: text columns of the telemetry (a fleet's ``drone``: the drone's name)
_TEXT = ("drone",)
_CATEGORIES = {"phase": PHASES, "stage": STAGES}


class FlightResult:
    """The outcome of ``Mission.run()``.

    - ``kpis``: dict of KPI name -> float (SI units, names from ``kpis.py``)
    - ``telemetry``: pandas DataFrame indexed by simulated time (s)
    - ``events``: list of dicts (t, kind, ...): stage changes, crash, battery, probe errors
    - ``scenario``: JSON-ready description of what was flown (drone, pilot, seed...)
    - ``energy_breakdown``: J per energy component and sub-component
    - ``end_reason``: "landed", "time", "battery_depleted", "crashed", "time_cap", "diverged",
      "wall_time" (stopped by ``Mission(max_wall_s=...)``)
    - ``probe_samples``: one DataFrame per probe, at the probe's own period
    - ``probe_errors``: failures of probes or subscribers (the flight went on)
    - ``cache``: where the flight cache got it (``pytest_flockai.cache``), or None
    - ``policies``: the policies as flown, by name (each is a copy of the one passed to the
      ``Mission``, which stays as it was); empty on a result read from the flight cache or
      sent back from a worker process
    """
    # Set after the flight (absent on a result built by hand: readers use getattr).
    #: (n, 3) positions of the world's people
    people: np.ndarray
    #: the detection tasks' worst frames, drawn, by task
    ml_gallery: dict
    #: the detection tasks' truth and predictions (COCO form), by task
    ml_coco: dict

    cache: dict | None = None
    policies: Mapping = MappingProxyType({})      # set after a flown flight (docstring)
    verdicts: tuple = ()     # the budgets last checked against it (budgets.check/evaluate)

    def __init__(self, kpis: dict, telemetry: pd.DataFrame, events: list, scenario: dict,
                 energy_breakdown: dict, end_reason: str, wall_time_s: float = float("nan"), *,
                 probe_samples: dict[str, pd.DataFrame] | None = None,
                 probe_errors: list | None = None) -> None:
        self.kpis = kpis
        self.telemetry = telemetry
        self.events = events
        self.scenario = scenario
        self.energy_breakdown = energy_breakdown
        self.end_reason = end_reason
        self.wall_time_s = wall_time_s   # host time, never part of the KPIs
        self.probe_samples = dict(probe_samples or {})
        self.probe_errors = list(probe_errors or [])

    def __getstate__(self) -> dict:
        """Pickled (a sweep's worker, a copy) without ``policies``: they hold the flight."""
        state = dict(self.__dict__)
        state.pop("policies", None)
        return state

    def _repr_html_(self) -> str:
        """In a notebook: the headline KPIs, the budgets checked and the path (SVG)."""
        return _notebook.flight_html(self)

    @property
    def sim_time_s(self) -> float:
        """Simulated seconds flown (NaN when the scenario does not say)."""
        return float(self.scenario.get("sim_time_s", float("nan")))

    @property
    def rtf(self) -> float:
        """Real-time factor of this run: simulated seconds per wall second."""
        return self.sim_time_s / self.wall_time_s if self.wall_time_s > 0 else float("nan")

    def to_dict(self) -> dict:
        """JSON-ready (strict JSON: non-finite numbers become null)."""
        return {"scenario": self.scenario,
                "kpis": {k: _json_num(v) for k, v in self.kpis.items()},
                "energy_breakdown": {k: _json_num(v) for k, v in self.energy_breakdown.items()},
                "end_reason": self.end_reason,
                "events": self.events}

    # -- persistence --------------------------------------------------------
    def _header(self) -> dict:
        return {"format": FORMAT, "scenario": self.scenario, "kpis": self.kpis,
                "events": self.events, "energy_breakdown": self.energy_breakdown,
                "end_reason": self.end_reason, "probe_errors": self.probe_errors,
                "probe_samples": {name: {"t": df.index.tolist(),
                                         "columns": {c: df[c].tolist() for c in df.columns}}
                                  for name, df in self.probe_samples.items()}}

    def save(self, path: str | os.PathLike) -> Path:
        """Write this result; the format follows the extension (.csv, .parquet, .jsonl).

        The telemetry's row count and SHA-256 go into the header (the sidecar
        for .csv/.parquet, which is written after the data), and the header's
        own SHA-256 with it, so ``load`` refuses a truncated file, a tampered
        header, or data and sidecar from different saves."""
        p = _path(path, "FlightResult.save")
        ext = p.suffix.lower()
        if ext not in (".csv", ".parquet", ".jsonl"):
            raise ConfigError(f"FlightResult.save: path {str(p)!r} must end in .csv, .parquet or .jsonl")
        if p.is_dir():
            raise ConfigError(f"FlightResult.save: path {str(p)!r} is a folder; expected a "
                              f"file path ending in .csv, .parquet or .jsonl")
        try:
            p.parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise WriteError(f"FlightResult.save: cannot create folder {str(p.parent)!r} for "
                             f"{str(p)!r}: {exc.strerror or exc}") from None
        _remove_stale_temps(p)
        if ext == ".jsonl":
            lines = _jsonl_rows(self.telemetry)
            digest = hashlib.sha256()
            for line in lines:
                digest.update(line.encode("utf-8"))
            header = _sealed({**self._header(), "telemetry": {"rows": len(lines),
                                                              "sha256": digest.hexdigest()}})

            def write(fh):
                fh.write(json.dumps(header) + "\n")
                fh.writelines(lines)
            _atomic(p, write, text=True)
            return p
        if ext == ".parquet":
            try:
                import pyarrow  # noqa: F401
            except ImportError:
                raise ConfigError("FlightResult.save: Parquet needs pyarrow: pip install "
                                  "'pytest-flockai[parquet]' (or save as .csv)") from None
            _atomic(p, lambda fh: self.telemetry.to_parquet(fh), text=False)
        else:
            _atomic(p, lambda fh: self.telemetry.to_csv(fh, float_format="%.17g"), text=True)
        header = _sealed({**self._header(), "telemetry": {
            "file": p.name, "rows": int(len(self.telemetry)), "sha256": sha256_of(p)}})
        _atomic(_sidecar(p), lambda fh: json.dump(header, fh), text=True)
        return p

    @classmethod
    def load(cls, path: str | os.PathLike) -> FlightResult:
        """Read a saved result back; ConfigError naming the file for anything that does
        not check out (missing sidecar, truncated data, checksum or row count off)."""
        p = _path(path, "FlightResult.load")
        ext = p.suffix.lower()
        if ext not in (".csv", ".parquet", ".jsonl"):
            raise ConfigError(f"FlightResult.load: {str(p)!r} must end in .csv, .parquet or .jsonl")
        if not p.is_file():
            raise ConfigError(f"FlightResult.load: {str(p)!r} does not exist or is not a file")
        try:
            header, tel = _read(p, ext)
        except (OSError, ValueError, KeyError, TypeError, ImportError) as exc:
            if isinstance(exc, ConfigError):
                raise
            raise ConfigError(f"FlightResult.load: cannot read {str(p)!r}: "
                              f"{type(exc).__name__}: {exc}") from None
        tel.index = tel.index.astype(float)
        tel.index.name = "t"
        for c, cats in _CATEGORIES.items():
            if c in tel.columns:
                tel[c] = pd.Categorical(tel[c], categories=list(cats))
        for c in tel.columns:
            if c in _TEXT:
                tel[c] = tel[c].astype(str)
            elif c not in _CATEGORIES:
                tel[c] = tel[c].astype(float)
        samples = {name: pd.DataFrame(d["columns"], index=pd.Index(d["t"], name="t"), dtype=float)
                   for name, d in header.get("probe_samples", {}).items()}
        return cls(header["kpis"], tel, header["events"], header["scenario"],
                   header["energy_breakdown"], header["end_reason"], probe_samples=samples,
                   probe_errors=header.get("probe_errors", []))

    def __eq__(self, other) -> bool:
        if not isinstance(other, FlightResult):
            return NotImplemented
        if (_norm(self.kpis) != _norm(other.kpis) or self.end_reason != other.end_reason
                or _norm(self.energy_breakdown) != _norm(other.energy_breakdown)
                or json.dumps(self.events, sort_keys=True) != json.dumps(other.events, sort_keys=True)
                or json.dumps(self.scenario, sort_keys=True) != json.dumps(other.scenario, sort_keys=True)):
            return False
        if not self.telemetry.equals(other.telemetry):
            return False
        if set(self.probe_samples) != set(other.probe_samples):
            return False
        return all(self.probe_samples[k].equals(other.probe_samples[k]) for k in self.probe_samples)

    __hash__ = None  # type: ignore[assignment]  # unhashable: typeshed cannot say None here

    def __repr__(self):
        k = self.kpis
        return (f"FlightResult(end={self.end_reason!r}, flight_time_s={k.get('flight_time_s', 0):.1f}, "
                f"energy_total_j={k.get('energy_total_j', 0):.0f}, crashed={int(k.get('crashed', 0))})")


def _json_num(v):
    v = float(v)
    return v if math.isfinite(v) else None


def _py(x):
    return x.item() if hasattr(x, "item") else (str(x) if not isinstance(x, (int, float)) else x)


def _norm(d):
    return {k: ("nan" if isinstance(v, float) and v != v else v) for k, v in d.items()}


def _path(path, where: str) -> Path:
    if not isinstance(path, (str, os.PathLike)) or not os.fspath(path):
        raise ConfigError(f"{where}: path = {path!r} is not allowed; expected a file path "
                          f"ending in .csv, .parquet or .jsonl")
    return Path(path)


def _jsonl_rows(tel) -> list[str]:
    cols = list(tel.columns)
    return [json.dumps({"t": t, **{c: _py(x) for c, x in zip(cols, row)}}) + "\n"
            for t, row in zip(tel.index.tolist(), tel.itertuples(index=False))]


def _digest(header: dict) -> str:
    body = {k: v for k, v in header.items() if k != "sha256"}
    return hashlib.sha256(json.dumps(body, sort_keys=True).encode("utf-8")).hexdigest()


def _sealed(header: dict) -> dict:
    """The header with its own SHA-256 (of everything else in it)."""
    return {**header, "sha256": _digest(header)}


def _check_header(header, p: Path, src: str) -> dict:
    where = f"FlightResult.load: {src}"
    if not isinstance(header, dict) or header.get("format") != FORMAT:
        raise ConfigError(f"{where} is not a {FORMAT} header")
    tel = header.get("telemetry")
    if not isinstance(tel, dict) or not isinstance(tel.get("rows"), int) or "sha256" not in tel:
        raise ConfigError(f"{where} has no telemetry row count and checksum (saved by an older "
                          f"pytest-flockai?); save the flight again")
    if header.get("sha256") != _digest(header):
        raise ConfigError(f"{where}: sha256 = {header.get('sha256')!r} does not match its "
                          f"content; the header was changed after it was saved")
    missing = [k for k in ("kpis", "events", "scenario", "energy_breakdown", "end_reason")
               if k not in header]
    if missing or not isinstance(header["kpis"], dict):
        raise ConfigError(f"{where} lacks {', '.join(missing) or 'a kpis table'}")
    return tel


def _read(p: Path, ext: str):
    """(header, telemetry) of a saved flight, both checked."""
    if ext == ".jsonl":
        with open(p, encoding="utf-8") as fh:
            header = json.loads(fh.readline())
            info = _check_header(header, p, f"{str(p)!r} (first line)")
            lines = [line for line in fh if line.strip()]
        digest = hashlib.sha256("".join(lines).encode("utf-8")).hexdigest()
        _check_rows(p, len(lines), info, digest)
        tel = pd.DataFrame([json.loads(x) for x in lines]).set_index("t") if lines else pd.DataFrame()
        return header, tel
    side = _sidecar(p)
    if not side.is_file():
        raise ConfigError(f"FlightResult.load: the sidecar {str(side)!r} of {str(p)!r} does not "
                          f"exist; a saved .csv/.parquet flight is the pair data + <name>.json")
    with open(side, encoding="utf-8") as fh:
        header = json.load(fh)
    info = _check_header(header, p, f"sidecar {str(side)!r}")
    digest = sha256_of(p)
    tel = (pd.read_parquet(p) if ext == ".parquet"
           else pd.read_csv(p, index_col="t", **_CSV_FLOATS))
    _check_rows(p, len(tel), info, digest)
    return header, tel


def _check_rows(p: Path, rows: int, info: dict, digest: str) -> None:
    if digest != info["sha256"]:
        raise ConfigError(f"FlightResult.load: {str(p)!r}: telemetry sha256 = {digest} does not "
                          f"match the saved {info['sha256']}; the file is truncated, changed, or "
                          f"from another save than its header")
    if rows != info["rows"]:
        raise ConfigError(f"FlightResult.load: {str(p)!r}: rows = {rows} but the header says "
                          f"{info['rows']}")


def _remove_stale_temps(p: Path, age_s: float = STALE_TEMP_S) -> None:
    """Temporary files of an earlier save of ``p`` that a killed process left
    behind (untouched for ``age_s``; a live save keeps writing to its own)."""
    now = time.time()
    for tmp in p.parent.glob(f".{glob.escape(p.name)}*.tmp"):
        try:
            if now - tmp.stat().st_mtime > age_s:
                tmp.unlink()
        except OSError:
            pass


def _sidecar(p: Path) -> Path:
    return p.with_name(p.name + ".json")


def _atomic(path: Path, write, *, text: bool):
    atomic_write(path, write, text=text)
