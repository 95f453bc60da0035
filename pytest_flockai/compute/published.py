"""The published batch-1 latency measurements, and how the latency model compares to them.

``data/published_latency.csv`` (one row per measurement: computer, runtime, target,
precision, network, input, latency_ms, and where it was published) joined with
``data/latency_sources.csv`` (each source's ``half``: ``tuning`` or ``heldout``, assigned
by source before any efficiency was chosen) and with the networks' per-node costs
``data/networks/<network>-<input>.csv`` (``compute.graph``). ``predictions`` runs the
latency model on every usable row; ``summary`` gives the ratios predicted/published
per half, computer and runtime (what ``benchmarks/latency_validation.py`` prints).
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..errors import ConfigError
from . import runtimes as _rt
from .devices import DEVICES
from .graph import NetworkCost
from .predict import BAND_COVER, BAND_QUANTILE_ROWS, above_idle_w, params_for, roofline

DATA = Path(__file__).with_name("data")
TABLE = DATA / "published_latency.csv"
SOURCES = DATA / "latency_sources.csv"
NETWORKS = DATA / "networks"


@dataclass(frozen=True)
class Row:
    """One published measurement, with its source's half and its network's cost."""

    row_id: str
    source_id: str
    half: str
    computer: str
    runtime: str
    target: str
    precision: str
    network: str
    input: str
    latency_s: float
    cost: object = None          # a NetworkCost (None: no per-node summary for it)
    #: the CPU clock the source states the board ran at, where it differs from the datasheet
    cpu_clock_ghz: float | None = None
    #: when the row's source joined the table (``added`` in latency_sources.csv)
    added: str = ""
    #: the CPU threads the benchmark ran with, where the source or its code says so
    #: (Ultralytics' TF Lite rows: 1, see ``load_rows``); None: the runtime's default
    #: (``runtimes.DEFAULT_THREADS``: every core but for TF Lite)
    threads: int | None = None
    #: who published the row's source (``publisher`` in latency_sources.csv, the text before
    #: " ("): two revisions of one maker's guide are one publisher
    publisher: str = ""

    @property
    def group(self) -> str:
        return f"{self.runtime}/{self.target}/{self.precision}"

    @property
    def device(self):
        """The computer as measured: its datasheet, with the CPU at ``cpu_clock_ghz`` when
        the source states another clock (peaks scale with the clock)."""
        return at_cpu_clock(DEVICES[self.computer], self.cpu_clock_ghz)

    @property
    def deployment(self) -> _rt.Deployment:
        """The row's (runtime, target, precision, threads) resolved on ``device``."""
        return _rt.resolve(self.device, self.runtime, self.precision, self.target or None,
                           self.threads)


def at_cpu_clock(dev, clock_ghz: float | None):
    """``dev`` with its CPU unit at ``clock_ghz`` (its peaks scaled by the clock ratio);
    ``dev`` itself when ``clock_ghz`` is None or the datasheet's clock."""
    if not clock_ghz:
        return dev
    units = []
    for u in dev.units:
        if u.kind == "cpu" and u.clock_ghz > 0 and u.clock_ghz != clock_ghz:
            k = clock_ghz / u.clock_ghz
            u = replace(u, clock_ghz=clock_ghz, peak=tuple((p, v * k) for p, v in u.peak))
        units.append(u)
    return replace(dev, units=tuple(units))


def _read_csv(path: Path) -> list[dict]:
    with open(path, encoding="utf-8", newline="") as fh:
        return [r for r in csv.DictReader(line for line in fh if not line.startswith("#"))]


def network_cost(network: str, size: str, folder: Path = NETWORKS):
    """The per-node cost of ``network`` at input ``size`` (None when not summarised)."""
    p = folder / f"{network}-{size}.csv"
    if not p.is_file():
        return None
    return NetworkCost.from_csv(p)


def load_rows(table: Path = TABLE, sources: Path = SOURCES, networks: Path = NETWORKS
              ) -> tuple[list[Row], list[str]]:
    """(usable rows, why each skipped row was skipped)."""
    if not table.is_file() or not sources.is_file():
        return [], [f"no published table ({table.name} / {sources.name} absent)"]
    srcs = _read_csv(sources)
    halves = {s["source_id"]: s["half"].strip() for s in srcs}
    added = {s["source_id"]: (s.get("added") or "").strip() for s in srcs}
    pubs = {s["source_id"]: (s.get("publisher") or "").split(" (")[0].strip() for s in srcs}
    rows, skipped, costs = [], [], {}
    for r in _read_csv(table):
        rid = r.get("row_id", "?")
        half = halves.get(r["source_id"])
        if half not in ("tuning", "heldout"):
            raise ConfigError(f"{table.name}: row {rid}: source_id = {r['source_id']!r} has no "
                              f"half in {sources.name}; allowed halves: tuning, heldout")
        if r["computer"] not in DEVICES:
            skipped.append(f"{rid}: computer {r['computer']!r} has no profile")
            continue
        key = (r["network"], r["input"])
        if key not in costs:
            costs[key] = network_cost(*key, folder=networks)
        if costs[key] is None:
            skipped.append(f"{rid}: no network summary {key[0]}-{key[1]}.csv")
            continue
        try:
            _rt.resolve(DEVICES[r["computer"]], r["runtime"], r["precision"], r["target"] or None)
        except ConfigError as e:
            skipped.append(f"{rid}: {e}")
            continue
        clock = (r.get("cpu_clock_ghz") or "").strip()
        try:
            ghz = float(clock) if clock else None
        except ValueError:
            ghz = -1.0
        if ghz is not None and not (0.1 <= ghz <= 10.0):
            raise ConfigError(f"{table.name}: row {rid}: cpu_clock_ghz = {clock!r} is not "
                              f"allowed; expected a clock in GHz between 0.1 and 10, or empty")
        raw = (r.get("threads") or "").strip()
        threads = int(raw) if raw.isdigit() else (None if not raw else -1)
        cores = DEVICES[r["computer"]].unit("cpu").cores if r["target"] == "cpu" else 0
        if threads is not None and not 1 <= threads <= cores:
            raise ConfigError(f"{table.name}: row {rid}: threads = {raw!r} is not allowed; "
                              f"expected empty (the runtime's default) or, for a "
                              f"cpu row, an int in 1..{cores}")
        rows.append(Row(rid, r["source_id"], half, r["computer"], r["runtime"],
                        r["target"], r["precision"], r["network"], r["input"],
                        float(r["latency_ms"]) / 1e3, costs[key], ghz, added[r["source_id"]],
                        threads, pubs[r["source_id"]]))
    return rows, skipped


#: profiles of one board in another power mode (a board never tuned leaves them out together:
#: ``tuning.loco``)
BOARD = {"jetson-nano-5w": "jetson-nano", "jetson-nano-10w": "jetson-nano",
         "jetson-orin-nano-super": "jetson-orin-nano"}


def board_of(computer: str) -> str:
    """The board a computer profile is a power mode of (``BOARD``), else itself."""
    return BOARD.get(computer, computer)


def predict_row(row: Row, table: dict) -> float:
    """Predicted seconds of one row with the efficiency table ``table``."""
    dev = row.device
    dep = row.deployment
    return roofline(row.cost, dev, dep, params_for(table, dep))[0]


def ratios(rows: list[Row], table: dict) -> np.ndarray:
    """predicted / published per row."""
    return np.array([predict_row(r, table) / r.latency_s for r in rows])


def _stats(r: np.ndarray) -> dict:
    a = np.abs(np.log(r))
    worst = r[int(np.argmax(a))]
    return {"n": int(r.size), "median_ratio": float(np.exp(np.median(np.log(r)))),
            "median_abs_ln": float(np.median(a)), "worst_ratio": float(worst),
            "within_2x": int(np.sum(a <= math.log(2.0)))}


def summary(rows: list[Row], table: dict) -> dict:
    """{half: {"all": stats, "computer": {name: stats}, "runtime": {name: stats},
    "computer/runtime": {...}}} of the ratios predicted/published."""
    out: dict = {}
    r = ratios(rows, table) if rows else np.array([])
    for half in ("tuning", "heldout"):
        idx = [i for i, x in enumerate(rows) if x.half == half]
        if not idx:
            continue
        h: dict = {"all": _stats(r[idx])}
        for label, key in (("computer", lambda x: x.computer), ("runtime", lambda x: x.runtime),
                           ("computer/runtime", lambda x: f"{x.computer}/{x.runtime}")):
            groups: dict[str, list[int]] = {}
            for i in idx:
                groups.setdefault(key(rows[i]), []).append(i)
            h[label] = {k: _stats(r[v]) for k, v in sorted(groups.items())}
        out[half] = h
    return out


def band_of(values) -> dict:
    """{"min", "max", "lo", "hi", "n"} of published/predicted ratios: ``lo``..``hi`` is what
    ``LatencyPrediction.band`` scales by: the central ``BAND_COVER`` of them (5th to 95th
    percentile) with ``BAND_QUANTILE_ROWS`` or more, else their whole range."""
    v = np.asarray(values, dtype=float)
    tail = (1.0 - BAND_COVER) / 2.0
    lo, hi = ((float(np.quantile(v, tail)), float(np.quantile(v, 1.0 - tail)))
              if v.size >= BAND_QUANTILE_ROWS else (float(v.min()), float(v.max())))
    return {"min": float(v.min()), "max": float(v.max()), "lo": lo, "hi": hi, "n": int(v.size)}


def bands(rows: list[Row], table: dict) -> dict:
    """Held-out published/predicted ranges per ``computer/runtime``, per ``computer/*/target``
    (every runtime of that computer on that unit) and per ``*/target`` (what
    ``LatencyPrediction.band`` scales the prediction by), each with its row count ``n`` and
    the number of publishers its rows come from (``sources``)."""
    held = [x for x in rows if x.half == "heldout"]
    if not held:
        return {}
    inv = 1.0 / ratios(held, table)
    out: dict = {}
    for _label, key in (("cr", lambda x: f"{x.computer}/{x.runtime}"),
                       ("ct", lambda x: f"{x.computer}/*/{x.target}"),
                       ("t", lambda x: f"*/{x.target}")):
        groups: dict[str, list[float]] = {}
        who: dict[str, set[str]] = {}
        for x, v in zip(held, inv):
            groups.setdefault(key(x), []).append(float(v))
            who.setdefault(key(x), set()).add(x.publisher or x.source_id)
        for k, v in groups.items():
            out[k] = {**band_of(v), "sources": len(who[k])}
    return out


ENERGY = DATA / "energy_published.csv"


def energy_check(table: dict, path: Path = ENERGY, networks: Path = NETWORKS) -> list[dict]:
    """Energy per inference, predicted against the published watt-meter figures.

    Per row of ``energy_published.csv`` whose computer, deployment and network are known:
    the published energy (``energy_j``, else ``power_w`` x latency) against the predicted
    latency x the computer's busy power (both whole-board energy per inference), and, where
    the source gives the idle power too, the above-idle energies."""
    if not path.is_file():
        return []
    out = []
    for r in _read_csv(path):
        cost = network_cost(r["network"], r["input"], networks)
        if r["computer"] not in DEVICES or cost is None:
            out.append({"id": r["energy_id"], "skipped": "no profile or network summary"})
            continue
        dev = DEVICES[r["computer"]]
        row = Row(r["energy_id"], r["source_id"], "energy", r["computer"], r["runtime"],
                  r["target"], r["precision"], r["network"], r["input"], 1.0, cost)
        try:
            secs = predict_row(row, table)
        except ConfigError as e:
            out.append({"id": r["energy_id"], "skipped": str(e)})
            continue
        lat = float(r["latency_ms"]) / 1e3
        pub = float(r["energy_j"]) if r.get("energy_j") else float(r["power_w"]) * lat
        extra_w = above_idle_w(dev, row.deployment)
        busy_w = dev.idle_w + extra_w
        rec = {"id": r["energy_id"], "computer": r["computer"], "deployment": row.group,
               "network": f"{r['network']}-{r['input']}", "published_j": pub,
               "predicted_j": secs * busy_w, "ratio": secs * busy_w / pub,
               "latency_ratio": secs / lat}
        if r.get("idle_w") and r.get("power_w"):
            above_w = float(r["power_w"]) - float(r["idle_w"])
            rec["above_idle_ratio"] = secs * extra_w / (above_w * lat)
            rec["power_above_idle_ratio"] = extra_w / above_w
        out.append(rec)
    return out


__all__ = ["ENERGY", "NETWORKS", "at_cpu_clock", "band_of", "board_of", "energy_check", "SOURCES", "TABLE", "Row", "bands", "load_rows", "network_cost",
           "predict_row", "ratios", "summary"]
