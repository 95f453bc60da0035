"""Mavic 2 Pro power and endurance versus airspeed (0-72 km/h) and hover versus payload.

Every point is a simulated flight: a straight level leg at constant speed
(or a hover), the mean electrical power taken over the steady part from the
telemetry (the battery's drain: load plus the pack's I^2 R loss), and endurance =
usable battery energy / that power.

    python benchmarks/energy_curve.py
"""

from __future__ import annotations

import pytest_flockai as fa


class SpeedNotReached(Exception):
    """The leg never settles at the asked speed (above what the drone holds level)."""


def steady_power(speed_mps: float, payload_kg: float = 0.0, steady_s: float = 30.0) -> float:
    d = fa.drone("dji-mavic-2-pro", payload_kg=payload_kg)
    if speed_mps <= 0:
        pilot = fa.pilots.Hover(altitude=20.0, duration=steady_s + 10.0)
    else:
        pilot = fa.pilots.Waypoints([(speed_mps * (steady_s + 30.0), 0.0, 20.0)], speed=speed_mps)
    r = fa.Mission(d, pilot, until=10.0 + 20.0 / 2.0 + steady_s + 15.0, return_home=False).run()
    tel = r.telemetry
    pil = tel[tel.stage == "pilot"]
    if speed_mps > 0:
        top = float(pil.vx.max())
        pil = pil[(pil.vx - speed_mps).abs() < 0.05 * speed_mps + 0.1]
        if len(pil) < 2:            # the drone never holds this speed: no steady power to give
            raise SpeedNotReached(f"{speed_mps * 3.6:.0f} km/h not held (top {top * 3.6:.1f} km/h)")
    else:
        pil = pil[pil.index > pil.index[0] + 5.0]
    # the battery's drain: the load's power plus the pack's own I^2 R loss (energy_j counts both)
    drain_w = (pil.energy_j.iloc[-1] - pil.energy_j.iloc[0]) / (pil.index[-1] - pil.index[0])
    return float(drain_w), d.battery.energy_j


def main():
    print("Mavic 2 Pro, no wind: electrical power and endurance vs airspeed (simulated)")
    print(f"{'km/h':>6s} {'m/s':>6s} {'power W':>9s} {'endurance min':>14s}")
    rows = []
    for kmh in (0, 10, 20, 25, 30, 40, 50, 60, 72):
        v = kmh / 3.6
        try:
            p, e = steady_power(v)
        except SpeedNotReached as exc:
            print(f"{kmh:6.0f} {v:6.2f} {'-':>9s} {'-':>14s}   {exc}")
            continue
        rows.append((kmh, p, e / p / 60))
        print(f"{kmh:6.0f} {v:6.2f} {p:9.1f} {e / p / 60:14.1f}")
    best = max(rows, key=lambda r: r[2])
    print(f"longest endurance at {best[0]} km/h: {best[2]:.1f} min (DJI: 31 min at 25 km/h, 29 min hover)")
    print()
    print("Mavic 2 Pro hover power and endurance vs payload (simulated)")
    print(f"{'payload g':>10s} {'power W':>9s} {'endurance min':>14s}")
    for g in (0, 100, 200, 300, 400, 500):
        p, e = steady_power(0.0, payload_kg=g / 1000.0)
        print(f"{g:10.0f} {p:9.1f} {e / p / 60:14.1f}")


if __name__ == "__main__":
    main()
