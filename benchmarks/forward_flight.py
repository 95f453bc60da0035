"""Forward-flight model choice (issue 30): the cruise-over-hover gain of every drone with a
maker's "flight time at X km/h" row, under three wake-interference laws, judged on the
TUNING drones only (held-out drones printed apart).

- ``immersion``: the shipped ``energy.rotors.wake_immersion`` (the aft disc's depth in the fore
  wake, 1 - h / D with h = L (V_ax + v_i) / V_par);
- ``skew2``: the former weighting, the wake skew angle squared, V_par^2 / (V_par^2 + (V_ax + v_i)^2);
- ``none``: no aft-rotor ingestion (Glauert's induced power per rotor only).

Hover rows do not depend on the law (V_par = 0), so each drone hovers once.

``--curve BLUEPRINT`` prints instead the drone's electrical power in steady level flight
against speed under each law, next to a published power-vs-speed measurement of a quadrotor
of the same class (``pytest_flockai.airframe.power_curves``).

    python benchmarks/forward_flight.py [--only NAME] [--laws immersion,skew2,none]
    python benchmarks/forward_flight.py --curve 3dr-solo
"""

from __future__ import annotations

import argparse
import statistics
import sys

from validation import CASES, HELD_OUT, TUNING, fly_until_empty

import pytest_flockai as fa
from pytest_flockai.airframe.power_curves import DI_FRANCO_2016, STOLAROFF_2018, relative
from pytest_flockai.energy import rotors

SHIPPED = rotors.wake_immersion


def skew_squared(distance_m, sink_m_s, vpar_m_s, diameter_m, maximum=max, minimum=min):
    """The former law: the share grows with the wake skew sin(chi)^2 (no geometry)."""
    s = maximum(sink_m_s, 0.0)
    return vpar_m_s * vpar_m_s / (vpar_m_s * vpar_m_s + s * s)


def no_ingestion(distance_m, sink_m_s, vpar_m_s, diameter_m, maximum=max, minimum=min):
    """No aft-rotor ingestion of the fore wake."""
    return 0.0


def level_power(blueprint: str, speed_m_s: float) -> float:
    """Mean electrical power (W) over the last 10 s of 45 s in level flight at ``speed_m_s``
    (0: hover) at 10 m."""
    pilot = (fa.pilots.Hover(altitude=10.0) if speed_m_s == 0.0 else
             fa.pilots.Waypoints([(5000.0, 0.0, 10.0)], speed=speed_m_s))
    tel = fa.Mission(fa.drone(blueprint), pilot, max_time_s=45.0).run().telemetry
    return float(tel.power_w[tel.index >= 35.0].mean())


LAWS = {"immersion": SHIPPED, "skew2": skew_squared, "none": no_ingestion}


def curve(blueprint: str, laws) -> None:
    """Print the drone's power against speed under each law and the published curves."""
    speeds = (0.0, 3.0, 5.0, 7.0, 9.0, 11.0, 13.0, 15.0)
    print(f"{'':22s}" + "".join(f"{v:>8.0f}" for v in speeds) + "  m/s (power over hover, %)")
    for law in laws:
        rotors.wake_immersion = LAWS[law]
        try:
            p = [level_power(blueprint, v) for v in speeds]
        finally:
            rotors.wake_immersion = SHIPPED
        miss = statistics.mean(abs(100 * (x / p[0] - 1 - relative(DI_FRANCO_2016, v)))
                               for v, x in zip(speeds[1:], p[1:]))
        print(f"{blueprint + ' ' + law:22s}" + "".join(f"{100 * (x / p[0] - 1):+8.1f}" for x in p)
              + f"  (hover {p[0]:.1f} W; Di Franco mean miss {miss:.1f} points)", flush=True)
    for name, data in (("Di Franco 2016", DI_FRANCO_2016), ("Stolaroff 2018", STOLAROFF_2018)):
        rel = [relative(data, v) for v in speeds]
        print(f"{name:22s}" + "".join("       -" if r is None else f"{100 * r:+8.1f}" for r in rel))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", default=None, help="fly only the blueprints whose name contains this")
    ap.add_argument("--laws", default="immersion,skew2,none", help="comma-separated: " + ", ".join(LAWS))
    ap.add_argument("--curve", default=None, help="power against speed of this blueprint instead")
    args = ap.parse_args(argv)
    laws = args.laws.split(",")
    if args.curve:
        return curve(args.curve, laws)
    speed = {bp: (kmh, pub, split) for bp, kmh, pay, pub, _, _, split in CASES if kmh is not None}
    hover = {bp: pub for bp, kmh, pay, pub, _, _, _ in CASES if kmh is None and pay == 0.0 and bp in speed}
    rows = []
    for bp, (kmh, pub, split) in speed.items():
        if bp not in hover or (args.only and args.only not in bp):
            continue
        h_min, _ = fly_until_empty(bp, None, 0.0)
        row = {"bp": bp, "split": split, "maker": 100.0 * (pub / hover[bp] - 1.0)}
        for law in laws:
            rotors.wake_immersion = LAWS[law]
            try:
                c_min, _ = fly_until_empty(bp, kmh, 0.0)
            finally:
                rotors.wake_immersion = SHIPPED
            row[law] = 100.0 * (c_min / h_min - 1.0)
            row[law + "_err"] = 100.0 * (c_min / pub - 1.0)
        rows.append(row)
        print(f"{bp:28s} {split:8s} maker {row['maker']:+5.1f} %  " + "  ".join(
            f"{law} {row[law]:+5.1f} % ({row[law] - row['maker']:+5.1f} pts, row {row[law + '_err']:+5.1f} %)"
            for law in laws), flush=True)
    for split in (TUNING, HELD_OUT):
        sel = [r for r in rows if r["split"] == split]
        if not sel:
            continue
        for law in laws:
            d = [abs(r[law] - r["maker"]) for r in sel]
            e = [abs(r[law + "_err"]) for r in sel]
            print(f"{split:8s} {law:9s} gain: mean |diff| {statistics.mean(d):4.1f} pts, "
                  f"{sum(x <= 5.0 for x in d)}/{len(d)} within 5; speed rows mean |error| "
                  f"{statistics.mean(e):4.1f} %")
    return rows


if __name__ == "__main__":
    main(sys.argv[1:])
