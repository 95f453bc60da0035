"""Validation table (issue 15): endurance predicted by today's model against the makers' figures.

Each blueprint is flown until its battery is depleted (``until="battery_depleted"``):
hovering at 10 m, and, where the maker publishes a flight time at a stated speed,
in level flight at that speed. Nothing is fitted per drone: the DJI rows are datasheet-level
blueprints (a ``[datasheet]`` table of the maker's figures; ``airframe/datasheet.py`` derives
the rest with one set of global constants), the Mavic 2 Pro as ``dji-mavic-2-pro-datasheet``.
The Crazyflie (brushed coreless motors, outside the brushless motor model) keeps its
system-identified blueprint with a fitted motor efficiency, so the mean errors are given with
and without it.

    python benchmarks/validation.py
"""

from __future__ import annotations

import time

import pytest_flockai as fa

# (blueprint, flight, speed km/h or None for hover, payload kg, published min, what the maker says, source)
CASES = [
    ("crazyflie-2-1", "hover", None, 0.0, 7.0, "flight time up to 7 min, speed not stated",
     "Bitcraze Crazyflie 2.1 datasheet", True),
    ("dji-mini-3-pro", "hover", None, 0.0, 30.0, "max hovering time 30 min",
     "https://www.dji.com/mini-3-pro/specs", False),
    ("dji-mini-3-pro", "21.6 km/h", 21.6, 0.0, 34.0, "max flight time 34 min at 21.6 km/h",
     "https://www.dji.com/mini-3-pro/specs", False),
    ("dji-air-2s", "hover", None, 0.0, 30.0, "max hovering time 30 min",
     "https://www.dji.com/air-2s/specs", False),
    ("dji-mavic-2-pro-datasheet", "hover", None, 0.0, 29.0, "max hovering time 29 min",
     "https://www.dji.com/mavic-2/info", False),
    ("dji-mavic-2-pro-datasheet", "25 km/h", 25.0, 0.0, 31.0, "max flight time 31 min at 25 km/h",
     "https://www.dji.com/mavic-2/info", False),
    ("dji-phantom-4-pro-v2", "hover", None, 0.0, 30.0, "max flight time approx. 30 min, speed not stated",
     "https://www.dji.com/phantom-4-pro-v2/specs", False),
    ("dji-inspire-2", "hover + X4S", None, 0.253, 27.0, "max flight time approx. 27 min with Zenmuse X4S",
     "https://www.dji.com/inspire-2/info#specs", False),
    ("dji-matrice-300-rtk", "hover", None, 0.0, 55.0, "max flight time 55 min, speed not stated",
     "https://enterprise.dji.com/matrice-300/specs", False),
]


def fly_until_empty(blueprint: str, speed_kmh: float | None, payload_kg: float):
    """Fly one blueprint until the battery is depleted; returns (minutes, mission result)."""
    d = fa.drone(blueprint, payload_kg=payload_kg)
    if speed_kmh is None:
        pilot = fa.pilots.Hover(altitude=10.0)
    else:
        pilot = fa.pilots.Waypoints([(90000.0, 0.0, 10.0)], speed=speed_kmh / 3.6)
    r = fa.Mission(d, pilot, until="battery_depleted").run()
    return r.kpis["flight_time_s"] / 60.0, r


def main():
    print("Endurance until the battery is depleted, datasheet-level model, no per-drone fitting")
    print(f"{'drone':22s} {'mass kg':>8s} {'flight':>12s} {'published':>10s} {'predicted':>10s} "
          f"{'error %':>8s}  fitted  {'end':16s} {'wall s':>6s}")
    rows = []
    for bp, flight, kmh, payload, published, _said, _src, fitted in CASES:
        t0 = time.perf_counter()
        minutes, r = fly_until_empty(bp, kmh, payload)
        wall = time.perf_counter() - t0
        err = 100.0 * (minutes - published) / published
        mass = fa.drone(bp).airframe.mass_kg + payload
        rows.append((bp, err, fitted))
        print(f"{bp:22s} {mass:8.3f} {flight:>12s} {published:10.1f} {minutes:10.2f} {err:+8.1f}  "
              f"{'yes' if fitted else 'no':6s}  {r.end_reason:16s} {wall:6.0f}")
    all_mae = sum(abs(e) for _, e, _ in rows) / len(rows)
    unfitted = [abs(e) for _, e, f in rows if not f]
    print(f"mean absolute error, all {len(rows)} rows: {all_mae:.1f} %; "
          f"worst {max(abs(e) for _, e, _ in rows):.1f} %")
    print(f"mean absolute error, {len(unfitted)} rows of unfitted blueprints: "
          f"{sum(unfitted) / len(unfitted):.1f} %; worst {max(unfitted):.1f} %")


if __name__ == "__main__":
    main()
