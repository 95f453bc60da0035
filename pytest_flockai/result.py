"""FlightResult: what a flown mission hands back."""

from __future__ import annotations

import math

import pandas as pd


class FlightResult:
    """The outcome of ``Mission.run()``.

    - ``kpis``: dict of KPI name -> float (SI units, names from ``kpis.py``)
    - ``telemetry``: pandas DataFrame indexed by simulated time (s)
    - ``events``: list of dicts (t, kind, ...): phase changes, crash, battery...
    - ``scenario``: JSON-ready description of what was flown (drone, pilot, seed...)
    - ``energy_breakdown``: J per energy component and sub-component
    - ``end_reason``: "landed", "time", "battery_depleted", "crashed", "time_cap"
    """

    def __init__(self, kpis, telemetry: pd.DataFrame, events, scenario, energy_breakdown,
                 end_reason: str, wall_time_s: float = float("nan")):
        self.kpis = kpis
        self.telemetry = telemetry
        self.events = events
        self.scenario = scenario
        self.energy_breakdown = energy_breakdown
        self.end_reason = end_reason
        self.wall_time_s = wall_time_s   # host time, never part of the KPIs

    @property
    def sim_time_s(self) -> float:
        return float(self.scenario.get("sim_time_s", float("nan")))

    @property
    def rtf(self) -> float:
        """Real-time factor of this run: simulated seconds per wall second."""
        return self.sim_time_s / self.wall_time_s if self.wall_time_s > 0 else float("nan")

    def to_dict(self) -> dict:
        """JSON-ready: scenario, KPIs, energy breakdown, end reason and events."""
        return {"scenario": self.scenario,
                "kpis": {k: _json_num(v) for k, v in self.kpis.items()},
                "energy_breakdown": {k: _json_num(v) for k, v in self.energy_breakdown.items()},
                "end_reason": self.end_reason,
                "events": self.events}

    def __repr__(self):
        k = self.kpis
        return (f"FlightResult(end={self.end_reason!r}, flight_time_s={k.get('flight_time_s', 0):.1f}, "
                f"energy_total_j={k.get('energy_total_j', 0):.0f}, crashed={int(k.get('crashed', 0))})")


def _json_num(v):
    v = float(v)
    return v if math.isfinite(v) else None
