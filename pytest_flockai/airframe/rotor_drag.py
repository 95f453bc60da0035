"""Rotor drag (the H-force): the in-plane force on a rotor moving edgewise through the air.

Blade-element theory of a rotor in edgewise flow (Leishman, Principles of Helicopter
Aerodynamics, 2nd ed. 2006, ch. 5, profile power in forward flight; Johnson, Helicopter
Theory, 1980, ch. 5, the rotor in forward flight): the blades' profile drag gives an in-plane force opposing the in-plane
airspeed, to first order in the advance ratio mu = V_par / (Omega R)

    C_H = sigma C_d0 mu / 4,   H = C_H rho A (Omega R)^2 = (sigma C_d0 / 4) rho A (Omega R) V_par,

linear in the in-plane airspeed and growing with rotor speed, i.e. with sqrt(thrust),
the same structure as the "rotor drag" of Faessler, Franchi and Scaramuzza (IEEE RA-L
2018, eq. 3: -R D R^T v per rotor speed). Only the profile part is modelled; the
induced part from blade flapping (a rigid propeller's tip-path-plane tilt) is not.

``RotorDrag`` applies it every control tick (held over the tick's physics substeps, like
the rotor commands): per rotor, from the drone's velocity relative to the air (the
wind of this tick) plus the rotation's share omega x r at the rotor hub, and from that
rotor's present thrust (MuJoCo's filtered actuator state, Omega = sqrt(T / kf)). The sum
of the forces and their moments about the centre of mass goes into ``xfrc_applied``.

Energy: the work against H is the ``2 mu^2`` of the profile power's ``1 + 3 mu^2`` (C_P0 =
C_Q0 + mu C_H0 = (sigma C_d0 / 8)(1 + mu^2) + (sigma C_d0 / 8) 2 mu^2, Leishman ch. 5); with H in the dynamics the tilt that overcomes it
shows in the energy model's ``T V_ax`` term, so energy/rotors.py takes it out of the
profile term (``PROFILE_MU2_WITH_H``).
"""

from __future__ import annotations

import math

from ..clock import Clocked
from ..physics import RHO_SEA_LEVEL

#: sigma C_d0 when a blueprint gives no blade geometry: the datasheet model's blade
#: (airframe/datasheet.py: two blades of chord 0.15 R, sigma = 2 x 0.15 / pi, Brandt and
#: Selig AIAA 2011-1255; section drag 0.040 at Re 6e4, the UIUC APC 9x4.7 static anchor)
BLADE_DRAG_DEFAULT = 2.0 * 0.15 / math.pi * 0.040


def h_coefficient(blade_drag: float, diameter_m: float, kf: float, rho: float) -> float:
    """c in H = c sqrt(T) V_par (N per (sqrt(N) m/s)) of one rotor: (sigma Cd0 / 4) rho A R
    Omega with Omega = sqrt(T / kf_rho), kf given at sea level and scaled with rho."""
    r = 0.5 * diameter_m
    kf_rho = kf * rho / RHO_SEA_LEVEL
    return 0.25 * blade_drag * rho * math.pi * r * r * r / math.sqrt(kf_rho)


def h_force(blade_drag: float, diameter_m: float, kf: float, rho: float, thrust_n: float,
            v_par: float) -> float:
    """Magnitude (N) of one rotor's H-force at thrust T and in-plane airspeed V_par."""
    if thrust_n <= 0.0:
        return 0.0
    return h_coefficient(blade_drag, diameter_m, kf, rho) * math.sqrt(thrust_n) * v_par


def hubs(drone) -> list[tuple[float, float, float]]:
    """Body-frame (x, y, h) of every rotor hub: the layout's arm ends at the height of the
    top of the body above the centre of mass (airframe/mjspec.py)."""
    h = 0.5 * drone.airframe.body_size_m[2]
    return [(x, y, h) for x, y, _ in drone.rotor_layout()]


class RotorDrag(Clocked):
    """The H-force of every rotor as a clocked component (every control tick)."""

    every_tick = True

    def __init__(self, drone, state, act, xfrc, rho: float):
        """``act``: the rotors' filtered thrusts (MjData.act view), ``xfrc``: the drone
        body's row of MjData.xfrc_applied (world-frame force and torque at the CoM)."""
        rot = drone.rotor
        self.st, self.act, self.xfrc = state, act, xfrc
        self.c = h_coefficient(rot.blade_drag, rot.diameter_m, rot.thrust_coeff, rho)
        self.hubs = hubs(drone)
        xfrc[:] = 0.0

    def step(self, t: float) -> None:
        s = self.st
        q, v, w = s.q, s.v, s.w
        qw, qx, qy, qz = q[3], q[4], q[5], q[6]
        # body-to-world rotation matrix from the unit quaternion
        r00, r01, r02 = 1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qw * qz), 2 * (qx * qz + qw * qy)
        r10, r11, r12 = 2 * (qx * qy + qw * qz), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qw * qx)
        r20, r21, r22 = 2 * (qx * qz - qw * qy), 2 * (qy * qz + qw * qx), 1 - 2 * (qx * qx + qy * qy)
        ax, ay, az = v[0] - w[0], v[1] - w[1], v[2] - w[2]
        bx = r00 * ax + r10 * ay + r20 * az           # air-relative velocity, body frame
        by = r01 * ax + r11 * ay + r21 * az
        p, qq, rr = v[3], v[4], v[5]                   # free joint: body-frame angular velocity
        c = self.c
        fx = fy = mx = my = mz = 0.0
        for (x, y, h), T in zip(self.hubs, self.act.tolist()):
            if T <= 0.0:
                continue
            k = -c * math.sqrt(T)
            hx = k * (bx + qq * h - rr * y)            # in-plane part of v + omega x r
            hy = k * (by + rr * x - p * h)
            fx += hx
            fy += hy
            mx -= h * hy
            my += h * hx
            mz += x * hy - y * hx
        xf = self.xfrc
        xf[0], xf[1], xf[2] = r00 * fx + r01 * fy, r10 * fx + r11 * fy, r20 * fx + r21 * fy
        xf[3] = r00 * mx + r01 * my + r02 * mz
        xf[4] = r10 * mx + r11 * my + r12 * mz
        xf[5] = r20 * mx + r21 * my + r22 * mz
