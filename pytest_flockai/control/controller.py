"""Cascaded flight controller: position -> velocity -> attitude -> body rates -> mixer.

Gains come from the airframe, so a new blueprint flies without tuning:

- the rate loop's bandwidth is set by the motor time constant and the control
  period (a first-order lag tau_eff = tau_motor + T_control; K_rate = 0.5 /
  tau_eff gives a damping ratio near 0.7), and torques are J * K_rate * error,
  so inertia scales out;
- each outer loop is 3x slower than the one inside it (damping ~0.87 for
  cascaded P loops);
- the tilt limit and the vertical acceleration limits come from the
  blueprint's max tilt and thrust-to-weight ratio.

Attitude uses the geometric error on SO(3) (Lee, Leok and McClamroch, 2010),
so large yaw and tilt errors stay well defined. The velocity loop is PI with
conditional integration (no wind-up while the thrust or tilt is saturated).
The mixer inverts the rotor allocation and, when a rotor saturates, keeps
roll/pitch first (moving the collective if it can), then scales yaw.

The code is written on Python floats, not numpy: for 3-vectors a numpy call
costs more than the arithmetic (see benchmarks/flight_core.py).
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np

from ..physics import RHO_SEA_LEVEL, G

CASCADE_RATIO = 3.0


class ControllerParams(NamedTuple):
    """A controller's gains and limits as numbers (``CascadedController.batch_params``)."""

    mass: float
    J: np.ndarray
    fmax: float
    k_rate: float
    k_att: float
    k_yaw_rate: float
    k_yaw: float
    k_vel: float
    k_vel_i: float
    k_pos: float
    tan_tilt: float
    a_up: float
    a_down: float
    i_lim_h: float
    i_lim_z: float
    kd_h: float
    kd_v: float
    B: np.ndarray


@functools.lru_cache(maxsize=256)
def allocation(layout: tuple, k: float) -> list:
    """The mixer: the pseudo-inverse of [T, tau_x, tau_y, tau_z] = A f for rotors at
    ``layout`` ((x, y, spin) each) with torque/thrust ratio ``k``, as rows of floats
    (cached: a sweep builds a controller per variant on the same layout)."""
    A = np.array([[1.0] * len(layout), [y for _, y, _ in layout], [-x for x, _, _ in layout],
                  [-s * k for _, _, s in layout]])
    return [tuple(float(v) for v in row) for row in np.linalg.pinv(A)]


class CascadedController:
    def __init__(self, drone, control_dt: float, rho: float = RHO_SEA_LEVEL):
        self.dt = control_dt
        af, rot = drone.airframe, drone.rotor
        self.mass = drone.mass_kg
        self.J = tuple(af.inertia_kg_m2)
        n = af.rotor_count
        self.n = n
        self.fmax = rot.max_thrust_n * rho / RHO_SEA_LEVEL     # thrust scales with air density
        tau_eff = rot.time_constant_s + control_dt
        self.k_rate = 0.5 / tau_eff
        self.k_att = self.k_rate / CASCADE_RATIO
        self.k_yaw_rate = 0.5 * self.k_rate
        self.k_yaw = self.k_yaw_rate / CASCADE_RATIO
        self.k_vel = self.k_att / CASCADE_RATIO
        self.k_vel_i = 0.35 * self.k_vel * self.k_vel
        self.k_pos = self.k_vel / CASCADE_RATIO
        self.max_tilt = math.radians(af.max_tilt_deg)
        tw = drone.thrust_to_weight_at(rho)
        self.tan_tilt = math.tan(self.max_tilt)
        self.a_up = max(0.5, 0.8 * (tw - 1.0) * G)   # keep 20% of the margin for attitude
        self.a_down = 0.6 * G
        # the integral term's acceleration limits (m/s^2): horizontally up to the
        # tilt limit, so it can hold against any wind the airframe can fly in;
        # vertically 0.3 g (mass and thrust errors). The state is clamped to
        # limit / k_vel_i: the limit is on the acceleration the integral supplies.
        self.i_lim_h = G * self.tan_tilt / self.k_vel_i
        self.i_lim_z = 0.3 * G / self.k_vel_i
        # drag feed-forward: the reference velocity's expected body drag (still air),
        # 1/2 rho CdA / m with the frontal CdA horizontally and the top CdA vertically
        self.kd_h = 0.5 * rho * af.drag_area_m2[0] / self.mass
        self.kd_v = 0.5 * rho * af.drag_area_m2[2] / self.mass
        # allocation: [T, tau_x, tau_y, tau_z] = A f
        k = rot.torque_coeff / rot.thrust_coeff
        lay = drone.rotor_layout()
        self.B = list(allocation(tuple(tuple(r) for r in lay), k))
        self.gains = {"k_rate": self.k_rate, "k_att": self.k_att, "k_yaw_rate": self.k_yaw_rate,
                      "k_yaw": self.k_yaw, "k_vel": self.k_vel, "k_vel_i": self.k_vel_i,
                      "k_pos": self.k_pos, "max_tilt_rad": self.max_tilt}
        self.f = [0.0] * n
        self.reset()

    def batch_params(self) -> ControllerParams:
        """The gains, limits and allocation, for the batched backend's controller."""
        return ControllerParams(
            mass=self.mass, J=np.asarray(self.J, dtype=float), fmax=self.fmax, k_rate=self.k_rate,
            k_att=self.k_att, k_yaw_rate=self.k_yaw_rate, k_yaw=self.k_yaw, k_vel=self.k_vel,
            k_vel_i=self.k_vel_i, k_pos=self.k_pos, tan_tilt=self.tan_tilt, a_up=self.a_up,
            a_down=self.a_down, i_lim_h=self.i_lim_h, i_lim_z=self.i_lim_z, kd_h=self.kd_h,
            kd_v=self.kd_v, B=np.asarray(self.B, dtype=float))

    def reset(self):
        self.ix = self.iy = self.iz = 0.0
        self.collective = 0.0
        self.f = [0.0] * self.n

    def update(self, q, v, sp):
        """One control step.

        q: qpos (x y z qw qx qy qz), v: qvel (vx vy vz world; wx wy wz body),
        sp: setpoint list (px py pz vx vy vz ax ay az yaw). Returns rotor thrusts (N).
        """
        x, y, z, qw, qx, qy, qz = q
        vx, vy, vz, wx, wy, wz = v
        spx, spy, spz, rvx, rvy, rvz, sax, say, saz, yaw = sp
        kp, kv, ki = self.k_pos, self.k_vel, self.k_vel_i
        # position -> velocity setpoint (P + feedforward)
        vsx = rvx + kp * (spx - x)
        vsy = rvy + kp * (spy - y)
        vsz = rvz + kp * (spz - z)
        # velocity -> acceleration (PI + feedforward of the reference's acceleration and drag)
        ex, ey, ez = vsx - vx, vsy - vy, vsz - vz
        rs = math.sqrt(rvx * rvx + rvy * rvy + rvz * rvz)
        kh, kz = self.kd_h * rs, self.kd_v * rs
        ix, iy, iz = self.ix, self.iy, self.iz
        ax = sax + kv * ex + ki * ix + kh * rvx
        ay = say + kv * ey + ki * iy + kh * rvy
        az = saz + kv * ez + ki * iz + kz * rvz
        sat = False
        a_up = self.a_up
        if az > a_up:
            az, sat = a_up, True
        elif az < -self.a_down:
            az, sat = -self.a_down, True
        fz = az + G
        hmax = fz * self.tan_tilt
        h2 = ax * ax + ay * ay
        if h2 > hmax * hmax:
            s = hmax / math.sqrt(h2)
            ax *= s
            ay *= s
            sat = True
        if not sat:
            dt = self.dt
            lim, lz = self.i_lim_h, self.i_lim_z
            self.ix = min(lim, max(-lim, ix + ex * dt))
            self.iy = min(lim, max(-lim, iy + ey * dt))
            self.iz = min(lz, max(-lz, iz + ez * dt))
        # desired thrust direction b3d and attitude (yaw sp[9])
        nrm = math.sqrt(ax * ax + ay * ay + fz * fz)
        d2x, d2y, d2z = ax / nrm, ay / nrm, fz / nrm
        cy, sy = math.cos(yaw), math.sin(yaw)
        # b2d = b3d x b1c, b1c = (cy, sy, 0)
        b2x, b2y, b2z = -d2z * sy, d2z * cy, d2x * sy - d2y * cy
        n2 = math.sqrt(b2x * b2x + b2y * b2y + b2z * b2z)
        d1y_x, d1y_y, d1y_z = b2x / n2, b2y / n2, b2z / n2
        # b1d = b2d x b3d
        d0x = d1y_y * d2z - d1y_z * d2y
        d0y = d1y_z * d2x - d1y_x * d2z
        d0z = d1y_x * d2y - d1y_y * d2x
        # current rotation matrix columns r0 r1 r2 from the quaternion
        xx, yy, zz = qx * qx, qy * qy, qz * qz
        xy, xz, yz = qx * qy, qx * qz, qy * qz
        wxq, wyq, wzq = qw * qx, qw * qy, qw * qz
        r0x, r0y, r0z = 1 - 2 * (yy + zz), 2 * (xy + wzq), 2 * (xz - wyq)
        r1x, r1y, r1z = 2 * (xy - wzq), 1 - 2 * (xx + zz), 2 * (yz + wxq)
        r2x, r2y, r2z = 2 * (xz + wyq), 2 * (yz - wxq), 1 - 2 * (xx + yy)
        # e_R = 1/2 vee(Rd^T R - R^T Rd); M_ij = d_i . r_j
        m21 = d2x * r1x + d2y * r1y + d2z * r1z
        m12 = d1y_x * r2x + d1y_y * r2y + d1y_z * r2z
        m02 = d0x * r2x + d0y * r2y + d0z * r2z
        m20 = d2x * r0x + d2y * r0y + d2z * r0z
        m10 = d1y_x * r0x + d1y_y * r0y + d1y_z * r0z
        m01 = d0x * r1x + d0y * r1y + d0z * r1z
        erx, ery, erz = 0.5 * (m21 - m12), 0.5 * (m02 - m20), 0.5 * (m10 - m01)
        # attitude -> body rates -> torques (J K (w_sp - w) + w x J w)
        ka, kr = self.k_att, self.k_rate
        Jx, Jy, Jz = self.J
        tx = Jx * kr * (-ka * erx - wx) + (Jz - Jy) * wy * wz
        ty = Jy * kr * (-ka * ery - wy) + (Jx - Jz) * wz * wx
        tz = Jz * self.k_yaw_rate * (-self.k_yaw * erz - wz) + (Jy - Jx) * wx * wy
        # collective thrust along the current body z
        T = self.mass * (ax * r2x + ay * r2y + fz * r2z)
        if T < 0.0:
            T = 0.0
        self.collective = T
        # the mixer; unsaturated (the usual case) here, saturated in _mix
        fmax = self.fmax
        f = [b0 * T + b1 * tx + b2 * ty + b3 * tz for b0, b1, b2, b3 in self.B]
        for fi in f:
            if fi < 0.0 or fi > fmax:
                return self._mix(T, tx, ty, tz)
        self.f = f
        return f

    def _mix(self, T, tx, ty, tz):
        B, fmax = self.B, self.fmax
        f = [b0 * T + b1 * tx + b2 * ty + b3 * tz for b0, b1, b2, b3 in B]
        if min(f) >= 0.0 and max(f) <= fmax:
            self.f = f
            return f
        f = self.f = [0.0] * self.n
        n = self.n
        base = [B[i][0] * T for i in range(n)]
        rp = [B[i][1] * tx + B[i][2] * ty for i in range(n)]
        yw = [B[i][3] * tz for i in range(n)]
        lo, hi = min(rp), max(rp)
        b0 = base[0]
        if hi - lo <= fmax:
            # move the collective as little as needed to fit roll/pitch
            b0 = min(max(b0, -lo), fmax - hi)
            s_rp = 1.0
        else:
            b0 = 0.5 * fmax - 0.5 * (hi + lo)
            s_rp = fmax / (hi - lo)
        g = [b0 + s_rp * r for r in rp]
        s_y = 1.0
        for i in range(n):
            if yw[i] > 0.0:
                s_y = min(s_y, max(0.0, (fmax - g[i]) / yw[i]))
            elif yw[i] < 0.0:
                s_y = min(s_y, max(0.0, -g[i] / yw[i]))
        for i in range(n):
            fi = g[i] + s_y * yw[i]
            f[i] = 0.0 if fi < 0.0 else (fmax if fi > fmax else fi)
        return f
