"""Published electrical power against airspeed of small quadrotors in steady level flight,
the check of the forward-flight power curve (``benchmarks/forward_flight.py
--curve``, ``tests/energy/test_power_curve.py``).

Each curve is (airspeed m/s, total electrical power W) read off the paper's figure; the
readings are those of the drone_awe project's validation set
(https://github.com/rymanderson/drone_awe, ``validationdata.py``, Anderson et al., BYU), which
digitised the figures. Both drones are 1.3 kg quadrotors on 10x4.7 in propellers, the class
of the 3DR Solo (1.5 kg, 10 in propellers).
"""

from __future__ import annotations

#: Di Franco and Buttazzo, "Coverage path planning for UAVs photogrammetry with energy and
#: resolution constraints", J. Intell. Robot. Syst. 83 (2016): a 1.3 kg quadrotor (10x4.7 in
#: propellers), power measured at constant speed. Lowest power 7.5 % below hover at 6-7 m/s.
DI_FRANCO_2016 = (
    (0.26, 220.7), (1.74, 220.5), (2.88, 219.8), (4.87, 209.7), (5.90, 204.8), (6.89, 204.1),
    (7.85, 210.0), (8.86, 211.4), (9.65, 216.9), (10.81, 213.6), (12.01, 239.4), (13.29, 256.9),
    (13.51, 279.1), (14.62, 290.3), (15.03, 332.1),
)

#: Stolaroff et al., "Energy use and life cycle greenhouse gas emissions of drones for
#: commercial package delivery", Nature Communications 9, 409 (2018), Supplementary: a 1.3 kg
#: quadrotor (10x4.7 in propellers, 3S 5500 mAh), power against airspeed in flight tests (no
#: hover point: the slowest reading, 1.4 m/s, stands for it). Flat to 4.6 m/s, then rising.
STOLAROFF_2018 = (
    (1.36, 133.8), (1.72, 149.2), (1.77, 144.6), (1.92, 139.4), (2.18, 138.4), (2.44, 136.5),
    (2.79, 136.6), (3.10, 143.7), (3.46, 143.5), (3.87, 139.8), (4.36, 140.8), (4.64, 140.4),
    (4.90, 148.3), (5.85, 161.1), (6.28, 158.8), (6.54, 157.0), (7.15, 161.2), (7.82, 164.7),
    (8.49, 177.1), (9.18, 175.7), (9.77, 190.1), (10.26, 197.4), (10.69, 209.1), (11.13, 203.8),
    (11.59, 215.8),
)


def relative(curve, speed_m_s: float) -> float | None:
    """Power at ``speed_m_s`` over the curve's slowest reading, minus 1 (linear between
    readings; 0 below the slowest); None beyond the fastest reading."""
    pts = sorted(curve)
    base = pts[0][1]
    if speed_m_s <= pts[0][0]:
        return 0.0
    for (v0, p0), (v1, p1) in zip(pts, pts[1:]):
        if speed_m_s <= v1:
            return (p0 + (p1 - p0) * (speed_m_s - v0) / (v1 - v0)) / base - 1.0
    return None
