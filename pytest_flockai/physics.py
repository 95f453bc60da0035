"""Physical constants and small frame helpers shared across the package.

One place for the numbers every layer needs, so that no domain package
imports another just for a constant.
"""

from __future__ import annotations

#: m/s^2, standard gravity rounded as in most flight-control code (ISO 80000-3
#: gives 9.80665; the 0.03 % difference is below every other model error here)
G = 9.81

#: kg/m^3, air density of the ICAO Standard Atmosphere at sea level, 15 degC
RHO_SEA_LEVEL = 1.225


def to_body(q, x, y, z):
    """A world-frame vector in the body frame of the attitude quaternion q[3:7] (R^T v)."""
    qw, qx, qy, qz = q[3], q[4], q[5], q[6]
    xx, yy, zz = qx * qx, qy * qy, qz * qz
    xy, xz, yz = qx * qy, qx * qz, qy * qz
    wx, wy, wz = qw * qx, qw * qy, qw * qz
    return ((1 - 2 * (yy + zz)) * x + 2 * (xy + wz) * y + 2 * (xz - wy) * z,
            2 * (xy - wz) * x + (1 - 2 * (xx + zz)) * y + 2 * (yz + wx) * z,
            2 * (xz + wy) * x + 2 * (yz - wx) * y + (1 - 2 * (xx + yy)) * z)
