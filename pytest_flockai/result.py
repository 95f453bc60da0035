"""FlightResult: what a flown mission hands back, and how it is saved.

``save(path)`` writes the telemetry as CSV (``.csv``) or Parquet
(``.parquet``, needs the optional ``pyarrow``) plus a JSON sidecar
(``<path>.json``) with the scenario, KPIs, events, energy breakdown and the
probes' own samples; ``.jsonl`` writes JSON lines (a header line, then one
line per telemetry row) for streaming tools. ``FlightResult.load(path)``
reads any of them back; a reloaded result compares equal to the saved one.
Files are written atomically (temporary file, then rename).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pandas as pd

from ._io import atomic_write
from .errors import ConfigError
from .phases import PHASES, STAGES

FORMAT = "pytest-flockai-flight/1"
_CATEGORIES = {"phase": PHASES, "stage": STAGES}


class FlightResult:
    """The outcome of ``Mission.run()``.

    - ``kpis``: dict of KPI name -> float (SI units, names from ``kpis.py``)
    - ``telemetry``: pandas DataFrame indexed by simulated time (s)
    - ``events``: list of dicts (t, kind, ...): stage changes, crash, battery, probe errors
    - ``scenario``: JSON-ready description of what was flown (drone, pilot, seed...)
    - ``energy_breakdown``: J per energy component and sub-component
    - ``end_reason``: "landed", "time", "battery_depleted", "crashed", "time_cap", "diverged"
    - ``probe_samples``: one DataFrame per probe, at the probe's own period
    - ``probe_errors``: failures of probes or subscribers (the flight went on)
    - ``cache``: where the flight cache got it (``pytest_flockai.cache``), or None
    """

    cache: dict | None = None

    def __init__(self, kpis, telemetry: pd.DataFrame, events, scenario, energy_breakdown,
                 end_reason: str, wall_time_s: float = float("nan"), *, probe_samples=None,
                 probe_errors=None):
        self.kpis = kpis
        self.telemetry = telemetry
        self.events = events
        self.scenario = scenario
        self.energy_breakdown = energy_breakdown
        self.end_reason = end_reason
        self.wall_time_s = wall_time_s   # host time, never part of the KPIs
        self.probe_samples = dict(probe_samples or {})
        self.probe_errors = list(probe_errors or [])

    @property
    def sim_time_s(self) -> float:
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

    def save(self, path) -> Path:
        """Write this result; the format follows the extension (.csv, .parquet, .jsonl)."""
        p = Path(path)
        ext = p.suffix.lower()
        if ext not in (".csv", ".parquet", ".jsonl"):
            raise ConfigError(f"FlightResult.save: path {str(p)!r} must end in .csv, .parquet or .jsonl")
        p.parent.mkdir(parents=True, exist_ok=True)
        if ext == ".jsonl":
            def write(fh):
                fh.write(json.dumps(self._header()) + "\n")
                tel = self.telemetry
                cols = list(tel.columns)
                for t, row in zip(tel.index.tolist(), tel.itertuples(index=False)):
                    fh.write(json.dumps({"t": t, **{c: _py(x) for c, x in zip(cols, row)}}) + "\n")
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
        _atomic(_sidecar(p), lambda fh: json.dump(self._header(), fh), text=True)
        return p

    @classmethod
    def load(cls, path) -> "FlightResult":
        p = Path(path)
        ext = p.suffix.lower()
        if not p.exists():
            raise ConfigError(f"FlightResult.load: {str(p)!r} does not exist")
        try:
            if ext == ".jsonl":
                with open(p) as fh:
                    header = json.loads(fh.readline())
                    rows = [json.loads(line) for line in fh if line.strip()]
                tel = pd.DataFrame(rows).set_index("t") if rows else pd.DataFrame()
            else:
                with open(_sidecar(p)) as fh:
                    header = json.load(fh)
                if ext == ".parquet":
                    tel = pd.read_parquet(p)
                elif ext == ".csv":
                    tel = pd.read_csv(p, index_col="t")
                else:
                    raise ConfigError(f"FlightResult.load: {str(p)!r} must end in .csv, .parquet or .jsonl")
        except (OSError, ValueError, KeyError) as exc:
            if isinstance(exc, ConfigError):
                raise
            raise ConfigError(f"FlightResult.load: cannot read {str(p)!r}: {exc}") from None
        if header.get("format") != FORMAT:
            raise ConfigError(f"FlightResult.load: {str(p)!r} is not a {FORMAT} file")
        tel.index = tel.index.astype(float)
        tel.index.name = "t"
        for c, cats in _CATEGORIES.items():
            if c in tel.columns:
                tel[c] = pd.Categorical(tel[c], categories=list(cats))
        for c in tel.columns:
            if c not in _CATEGORIES:
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

    __hash__ = None

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


def _sidecar(p: Path) -> Path:
    return p.with_name(p.name + ".json")


def _atomic(path: Path, write, *, text: bool):
    atomic_write(path, write, text=text)
