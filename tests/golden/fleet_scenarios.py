"""Golden fleets: short fleet flights whose KPIs, end reasons, event counts and
telemetry sums are recorded in ``tests/golden/fleet_golden.json``
(``tests/mission/test_fleet_golden.py`` flies them again and compares).

Recorded before the fleet loop was made faster, so they prove that
speeding it up did not move behaviour. ``python tests/golden/fleet_scenarios.py``
re-records; do that only for an intended change of behaviour, and say why in the
commit.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pandas as pd

import pytest_flockai as fa

HERE = Path(__file__).resolve().parent
GOLDEN = HERE / "fleet_golden.json"
MAVIC = "dji-mavic-2-pro"


def _survey(n: int, offload=None, until="landed") -> fa.Fleet:
    area = ((0, 0), (80, 100))
    parts = fa.fleet.survey(area, n, altitude=15, spacing=20, speed=8)
    return fa.Fleet([fa.FleetDrone(f"drone-{i + 1}", fa.drone(MAVIC), p, pad=pad, seed=10 + i)
                     for i, (p, pad) in enumerate(parts)], area=area, swath_m=20,
                    offload=offload, until=until)


def _crossing() -> fa.Fleet:
    a = fa.pilots.Waypoints([(-40, 0, 20), (40, 0, 20)], speed=6)
    b = fa.pilots.Waypoints([(0, -40, 20), (0, 40, 20)], speed=6)
    return fa.Fleet([fa.FleetDrone("a", fa.drone(MAVIC), a, pad=(-40, 0), seed=1),
                     fa.FleetDrone("b", fa.drone(MAVIC), b, pad=(0, -40), seed=2)],
                    max_time_s=120.0)


def scenarios() -> dict:
    off = fa.fleet.Offload(period_s=0.5, frame_bytes=150_000, ground_station=(0, -30, 1))
    return {
        "survey-3": lambda: _survey(3),
        "survey-2-offload-timed": lambda: _survey(2, off, until=40.0),
        "crossing": _crossing,
        "crazyflies": lambda: fa.Fleet(
            [fa.FleetDrone("c1", fa.drone("crazyflie-2-1"), fa.pilots.Hover(1.0, 3.0)),
             fa.FleetDrone("c2", fa.drone("crazyflie-2-1"),
                           fa.pilots.Waypoints([(3, 1, 1.5), (3, 3, 1.5)], speed=1.0),
                           pad=(3, 0), seed=7)]),
    }


def summary(result) -> dict:
    kinds: dict = {}
    for e in result.events:
        key = f"{e['drone']}.{e['kind']}"
        kinds[key] = kinds.get(key, 0) + 1
    tel = result.telemetry
    sums = {c: float(np.nansum(tel[c].to_numpy(dtype=float))) for c in tel.columns
            if pd.api.types.is_numeric_dtype(tel[c].dtype)}
    return {"end_reason": result.end_reason, "kpis": result.kpis, "events": kinds,
            "telemetry_rows": int(len(tel)), "telemetry_sums": sums,
            "breakdown": result.energy_breakdown}


def fly(name: str) -> dict:
    return summary(scenarios()[name]().run())


def main(argv) -> int:
    out = {name: fly(name) for name in scenarios()}
    GOLDEN.write_text(json.dumps(out, indent=1, sort_keys=True, default=float) + "\n")
    print(f"recorded {len(out)} fleets into {GOLDEN}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
