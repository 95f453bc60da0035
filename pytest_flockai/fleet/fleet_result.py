"""The FleetResult: every drone's FlightResult, their KPIs prefixed with the
drone's name (``drone-2.flight_time_s``), fleet-wide KPIs (``fleet.*``), one
telemetry with a ``drone`` column and one event log with a ``drone`` field.

Fleet KPIs:
- ``fleet.makespan_s``: simulated time until the last drone's flight ended;
- ``fleet.min_separation_m``: the smallest distance between two airborne drones
  (infinite when never two were in the air at once: a single drone);
- ``fleet.coverage_fraction``: the share of the fleet's ``area`` that some drone
  passed over, within ``swath_m / 2`` (a square footprint) while flying its
  pilot's plan, from the telemetry (only with ``Fleet(area=..., swath_m=...)``);
- ``fleet.coverage_time_s``: from the first drone starting its pilot's plan to
  the last drone ending it (take-off, return and landing left out);
- ``fleet.crashes``, ``fleet.drones``, ``fleet.energy_total_j`` (the sum);
- ``fleet.inference_latency_p95_s``: over every drone's answered inferences (with tasks);
  with remote tasks, the shared ground station's ``link.queue_delay_p95_s``,
  ``ground.queue_delay_mean_s`` / ``_p95_s`` and ``ground.utilization``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pandas as pd

from .. import notebook as _notebook
from ..control.stages import TAKEOFF
from ..mission import collect
from ..policy.together import stations
from ..result import FlightResult
from .offload import ground_kpis

#: the coverage grid has at most this many cells along a side
MAX_GRID = 400
#: Hz: how often the separation of the airborne drones is measured
SEPARATION_HZ = 50.0


class FleetResult(FlightResult):
    """A ``FlightResult`` of the whole fleet; ``drones``: name -> that drone's FlightResult;
    ``stations``: each ground station's ``record()`` after the flight (a search together)."""

    drones: dict
    stations: Sequence[dict] = ()

    def _repr_html_(self) -> str:
        """In a notebook: the fleet KPIs, one row and one path colour per drone."""
        return _notebook.fleet_html(self)

    def __repr__(self):
        return (f"FleetResult({len(self.drones)} drones, end_reason={self.end_reason!r}, "
                f"makespan={self.kpis.get('fleet.makespan_s', math.nan):.1f} s)")


def build(fleet, runs, stats: dict, wall_s: float) -> FleetResult:
    ends = stats.get("t_end") or [r.shared.time for r in runs]
    drones = {}
    for r, t_end in zip(runs, ends):
        drones[r.vehicle.name] = collect.flight_result(r, r.mission, wall_s, t_end,
                                                       r.vehicle.end_reason or "time")
    kpis: dict = {}
    for name, res in drones.items():
        kpis.update({f"{name}.{k}": v for k, v in res.kpis.items()})
    tel = pd.concat([res.telemetry.assign(drone=name) for name, res in drones.items()])
    tel = tel.sort_index(kind="stable")
    kpis.update(fleet_kpis(fleet, drones, stats, ends, tel))
    for station in stations(runs):              # a search together (fa.policy.SharedSearch)
        kpis.update(station.kpis())
    events = sorted(({**e, "drone": name} for name, res in drones.items() for e in res.events),
                    key=lambda e: e["t"])
    energy = {f"{name}.{k}": v for name, res in drones.items()
              for k, v in res.energy_breakdown.items()}
    reasons = {res.end_reason for res in drones.values()}
    end = reasons.pop() if len(reasons) == 1 else ("crashed" if "crashed" in reasons else "mixed")
    scen = fleet.scenario()
    scen["sim_time_s"] = float(max(ends))
    out = FleetResult(kpis, tel, events, scen, energy, end, wall_s)
    out.drones = drones
    out.stations = [st.record() for st in stations(runs)]
    first = next(iter(drones.values()))
    out.people = getattr(first, "people", np.zeros((0, 3)))
    return out


def fleet_kpis(fleet, drones: dict, stats: dict, ends, tel) -> dict:
    sep = stats.get("min_separation_m", math.inf)
    out = {"fleet.drones": float(len(drones)),
           "fleet.makespan_s": float(max(ends)),
           "fleet.min_separation_m": float(sep),
           "fleet.crashes": float(sum(1 for r in drones.values() if r.end_reason == "crashed")),
           "fleet.energy_total_j": float(sum(r.kpis.get("energy_total_j", 0.0)
                                             for r in drones.values())),
           "fleet.coverage_time_s": coverage_time(drones.values())}
    if fleet.area is not None:
        out["fleet.coverage_fraction"] = coverage(fleet.area, fleet.swath_m, tel)
    off = stats.get("offload")
    if off is not None:
        out.update(off.kpis(list(drones), out["fleet.makespan_s"]))
    ground = stats.get("ground")
    if ground is not None:                 # the remote tasks' shared ground station
        out.update(ground_kpis(ground, out["fleet.makespan_s"]))
    lat = [e["latency_s"] for r in drones.values() for e in r.events
           if e["kind"] == "inference" and e["ok"]]
    if lat:
        out["fleet.inference_latency_p95_s"] = float(np.percentile(lat, 95))
    return out


class Separation:
    """``fleet.min_separation_m`` measured in flight: a flight-wide step of the loop
    (``mission.loop.fly``) at ``SEPARATION_HZ``: the smallest distance between two
    drones in the air (past take-off) at once; infinite while never two were."""

    def __init__(self):
        self.period_s = 1.0 / SEPARATION_HZ
        self.next_due = 0.0
        self.min_m = math.inf

    def step(self, t: float, drones) -> None:
        self.next_due += self.period_s
        live = [m for m in drones if m.active]
        if len(live) > 1:
            self.min_m = min(self.min_m, separation(live))


def separation(drones) -> float:
    """The smallest distance between two of ``drones`` in the air now (inf if < 2)."""
    pts = [m.s.q for m in drones if m.s.airborne and m.s.stage != TAKEOFF]
    best = math.inf                    # squared: sqrt is monotonic, one sqrt at the end
    for i in range(len(pts) - 1):
        ax, ay, az = pts[i][:3]
        for b in pts[i + 1:]:
            dx, dy, dz = ax - b[0], ay - b[1], az - b[2]
            d = dx * dx + dy * dy + dz * dz
            if d < best:
                best = d
    return math.sqrt(best)


def coverage_time(results) -> float:
    """First ``pilot`` stage start to last pilot end (``return``/``landing``/end), s."""
    starts, ends = [], []
    for res in results:
        t0 = next((e["t"] for e in res.events if e["kind"] == "stage" and e["stage"] == "pilot"),
                  None)
        if t0 is None:
            continue
        starts.append(t0)
        ends.append(next((e["t"] for e in res.events if e["kind"] == "stage" and e["t"] >= t0
                          and e["stage"] in ("return", "landing")), res.sim_time_s))
    return float(max(ends) - min(starts)) if starts else math.nan


def coverage(area, swath_m: float, tel: pd.DataFrame) -> float:
    """Share of ``area`` within ``swath_m / 2`` (square footprint) of a telemetry
    row flown in the ``pilot`` stage."""
    (x0, y0), (x1, y1) = area
    cell = max(swath_m / 4.0, (x1 - x0) / MAX_GRID, (y1 - y0) / MAX_GRID)
    nx, ny = max(1, int(math.ceil((x1 - x0) / cell))), max(1, int(math.ceil((y1 - y0) / cell)))
    grid = np.zeros((nx, ny), dtype=bool)
    rows = tel[tel["stage"] == "pilot"]
    half = 0.5 * swath_m
    for x, y in zip(rows["x"].to_numpy(), rows["y"].to_numpy()):
        i0 = int(math.floor((x - half - x0) / cell + 0.5))
        i1 = int(math.floor((x + half - x0) / cell - 0.5))
        j0 = int(math.floor((y - half - y0) / cell + 0.5))
        j1 = int(math.floor((y + half - y0) / cell - 0.5))
        if i1 < 0 or j1 < 0 or i0 >= nx or j0 >= ny:
            continue
        grid[max(i0, 0):min(i1, nx - 1) + 1, max(j0, 0):min(j1, ny - 1) + 1] = True
    return float(grid.mean())
