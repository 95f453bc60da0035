"""The core's trajectories, pilots, stage machine and cascaded controller in
``jax.numpy``, for one variant (``engine`` vmaps them over the batch).

Each function is the branch-free twin of the core's code it names
(``control/trajectory.py``, ``control/pilots.py``, ``control/stages.py``,
``control/controller.py``): the same equations, with ``jnp.where`` for the
core's ``if``. ``p`` is a variant's numbers (``params.variant``), ``s`` its
state (a dict of arrays).
"""

from __future__ import annotations

import jax.numpy as jnp

from ...control.stages import (
    DONE,
    LANDING,
    LANDING_OVERSHOOT,
    PILOT,
    RETURN,
    TAKEOFF,
    TOUCHDOWN_SPEED,
)
from ...control.trajectory import leg_timing
from ...physics import G


def _length(d):
    """|d| summed in the core's order (``math.sqrt(sum(c * c for c in d))``), so a leg's
    duration is the core's to the last bit and the stage switches on the same tick."""
    return jnp.sqrt(d[..., 0] * d[..., 0] + d[..., 1] * d[..., 1] + d[..., 2] * d[..., 2])


def leg(p0, p1, speed, accel, t):
    """``Leg(p0, p1, speed, accel).fill(t, sp)``: (pos, vel, acc, duration); the timing is
    the core's ``leg_timing``."""
    d = p1 - p0
    L = _length(d)
    ok = L > 1e-12
    Ls = jnp.where(ok, L, 1.0)
    u = jnp.where(ok, d / Ls, 0.0)
    v, ta, s_acc, t_cr, dur = leg_timing(Ls, speed, accel, jnp)
    dur = jnp.where(ok, dur, 0.0)
    r = dur - t
    s = jnp.where(t <= 0.0, 0.0, jnp.where(t < ta, 0.5 * accel * t * t, jnp.where(
        t < ta + t_cr, s_acc + v * (t - ta), jnp.where(t < dur, Ls - 0.5 * accel * r * r, Ls))))
    sv = jnp.where(t <= 0.0, 0.0, jnp.where(t < ta, accel * t, jnp.where(
        t < ta + t_cr, v, jnp.where(t < dur, accel * r, 0.0))))
    sa = jnp.where(t <= 0.0, 0.0, jnp.where(t < ta, accel, jnp.where(
        t < ta + t_cr, 0.0, jnp.where(t < dur, -accel, 0.0))))
    s, sv, sa = jnp.where(ok, s, 0.0), jnp.where(ok, sv, 0.0), jnp.where(ok, sa, 0.0)
    return p0 + s * u, sv * u, sa * u, dur


def path(starts_p, ends_p, speed, accel, t):
    """``waypoint_path(...).fill(t, sp)`` over legs (starts_p[i] -> ends_p[i]):
    (pos, vel, acc, done)."""
    L = _length(ends_p - starts_p)
    ok = L > 1e-12
    dur = jnp.where(ok, leg_timing(jnp.where(ok, L, 1.0), speed, accel, jnp)[4], 0.0)
    ends = [dur[0]]                                  # the core's running sum, in its order
    for k in range(1, dur.shape[0]):
        ends.append(ends[-1] + dur[k])
    starts = jnp.stack([jnp.zeros_like(dur[0])] + ends[:-1])
    i = jnp.clip(jnp.sum(t >= starts[1:]), 0, dur.shape[0] - 1)
    pos, vel, acc, _ = leg(starts_p[i], ends_p[i], speed, accel, t - starts[i])
    return pos, vel, acc, t >= ends[-1]


def pilot_update(p, s, t, kind):
    """The pilot's setpoint at t: (sp[0:9], done, t0, start) (Hover / Waypoints)."""
    t0, start = s["pilot_t0"], s["pilot_start"]
    if kind[0] == "hover":
        sp9 = jnp.concatenate([start, jnp.zeros(6)])
        return sp9, t - t0 >= p.pilot.duration, t0, start
    pts = p.pilot.points
    pos, vel, acc, done = path(jnp.concatenate([start[None], pts[:-1]]), pts, p.pilot.speed,
                               p.mission.accel, t - t0)
    sp9 = jnp.concatenate([pos, vel, acc])
    if kind[2]:                                          # loop: start over from the last point
        t0 = jnp.where(done, t, t0)
        start = jnp.where(done, pts[-1], start)
        done = jnp.zeros_like(done)
    return sp9, done, t0, start


def pilot_start(p, q, kind):
    """``pilot.start``: the position a Hover holds / a Waypoints path starts from."""
    if kind[0] == "hover":
        return jnp.stack([q[0], q[1], p.pilot.altitude])
    return q[:3]


def after_pilot(p, s, here, force):
    """``StageMachine._after_pilot``: (stage, leg p0, leg p1, leg speed)."""
    home = s["home"]
    away = jnp.hypot(here[0] - home[0], here[1] - home[1]) > 0.5
    ret = (p.mission.return_home | force) & away
    home_air = jnp.stack([home[0], home[1], here[2]])
    land_to = jnp.stack([here[0], here[1], home[2] - LANDING_OVERSHOOT])
    return (jnp.where(ret, RETURN, LANDING), here, jnp.where(ret, home_air, land_to),
            jnp.where(ret, p.pilot.return_speed, p.mission.descent_speed))


def stages(p, s, t, q, v, contact, kind):
    """``StageMachine.step``: the new setpoint, stage, leg and pilot state. In parts, so
    that the batch (``engine._stages``) computes the leg, the take-off's end and the
    pilot's end only on ticks where some variant needs them."""
    pil = pilot_update(p, s, t, kind)
    return combine(p, s, t, v, contact, pil, leg_setpoint(p, s, t),
                   takeoff_done(p, s, t, q, kind), after_pilot(p, s, pil[0][:3], False))


def leg_setpoint(p, s, t):
    """The leg stages' (take-off, return, landing) setpoint: (pos, vel, acc, duration)."""
    return leg(s["leg_p0"], s["leg_p1"], s["leg_speed"], p.mission.accel, t - s["t_stage"])


def takeoff_done(p, s, t, q, kind):
    """Take-off done: the pilot starts over the climb's setpoint (the pad, not where a
    wind pushed the drone: control/stages.py) and writes this tick's setpoint: (sp[0:9],
    pilot t0, pilot start)."""
    sp = s["sp"]
    s1 = {**s, "pilot_t0": t, "pilot_start": pilot_start(p, jnp.stack([sp[0], sp[1], q[2]]), kind)}
    ssp, _, st0, sstart = pilot_update(p, s1, t, kind)
    return ssp, st0, sstart


def combine(p, s, t, v, contact, pil, lg, take, aft):
    """``stages`` from its parts: the pilot's update ``pil``, the leg's setpoint ``lg``,
    the take-off's end ``take`` and what follows the pilot ``aft`` (each read only where
    it applies)."""
    stage, sp = s["stage"], s["sp"]
    psp, pdone, pt0, pstart = pil
    lpos, lvel, lacc, ldur = lg
    ssp, st0, sstart = take
    a_stage, a_p0, a_p1, a_spd = aft
    lsp = jnp.concatenate([lpos, lvel, lacc])
    ldone = t - s["t_stage"] >= ldur
    # return done: land from the end of the return leg
    l_p1 = jnp.stack([lpos[0], lpos[1], s["home"][2] - LANDING_OVERSHOOT])
    is_p, is_leg = stage == PILOT, (stage != PILOT) & (stage != DONE)
    to_pilot = is_leg & ldone & (stage == TAKEOFF)
    to_land = is_leg & ldone & (stage == RETURN)
    after = is_p & pdone
    sp9 = jnp.where(is_p, psp, jnp.where(to_pilot, ssp, jnp.where(is_leg, lsp, sp[:9])))
    yaw = jnp.where(is_p | to_pilot, p.pilot.yaw, sp[9])
    new_stage = jnp.where(after, a_stage, jnp.where(to_pilot, PILOT, jnp.where(to_land, LANDING, stage)))
    out = {**s, "sp": jnp.concatenate([sp9, yaw[None]]), "stage": new_stage,
           "pilot_t0": jnp.where(to_pilot, st0, jnp.where(is_p, pt0, s["pilot_t0"])),
           "pilot_start": jnp.where(to_pilot, sstart, jnp.where(is_p, pstart, s["pilot_start"])),
           "t_stage": jnp.where(after | to_land, t, s["t_stage"]),
           "leg_p0": jnp.where(after, a_p0, jnp.where(to_land, lpos, s["leg_p0"])),
           "leg_p1": jnp.where(after, a_p1, jnp.where(to_land, l_p1, s["leg_p1"])),
           "leg_speed": jnp.where(after, a_spd, jnp.where(to_land, p.mission.descent_speed,
                                                          s["leg_speed"]))}
    landed = (new_stage == LANDING) & contact & (jnp.abs(v[2]) < TOUCHDOWN_SPEED)
    out["stage"] = jnp.where(landed, DONE, out["stage"])
    out["t_land"] = jnp.where(landed, t, s["t_land"])
    return out, landed


def go_home(p, s, t, when):
    """``StageMachine.go_home`` (battery reserve) where ``when``."""
    st, p0, p1, spd = after_pilot(p, s, s["sp"][:3], True)
    return {**s, "stage": jnp.where(when, st, s["stage"]),
            "t_stage": jnp.where(when, t, s["t_stage"]),
            "leg_p0": jnp.where(when, p0, s["leg_p0"]), "leg_p1": jnp.where(when, p1, s["leg_p1"]),
            "leg_speed": jnp.where(when, spd, s["leg_speed"])}


def _clamp(x, lim):
    return jnp.minimum(lim, jnp.maximum(-lim, x))


def controller(c, integ, q, v, sp, dt):
    """``CascadedController.update`` with ``c = CascadedController.batch_params()``: (rotor
    thrusts (n,), new integrator state (3,))."""
    (T, tx, ty, tz), integ = wrench(c, integ, q, v, sp, dt)
    return mix(c.B, c.fmax, T, tx, ty, tz), integ


def wrench(c, integ, q, v, sp, dt, yaw_cs=None):
    """``controller`` up to the mixer: ((collective thrust, torques x y z), new integrator
    state); ``yaw_cs``: (cos, sin) of the yaw setpoint ``sp[9]`` if the caller has them."""
    pos, vel, quat, w = q[:3], v[:3], q[3:7], v[3:6]
    vs = sp[3:6] + c.k_pos * (sp[0:3] - pos)
    e = vs - vel
    rv = sp[3:6]
    rs = jnp.sqrt(jnp.sum(rv * rv))
    kd = jnp.stack([c.kd_h, c.kd_h, c.kd_v]) * rs
    a = sp[6:9] + c.k_vel * e + c.k_vel_i * integ + kd * rv
    sat_z = (a[2] > c.a_up) | (a[2] < -c.a_down)
    az = jnp.clip(a[2], -c.a_down, c.a_up)
    fz = az + G
    hmax = fz * c.tan_tilt
    h2 = a[0] * a[0] + a[1] * a[1]
    sat_h = h2 > hmax * hmax
    sc = jnp.where(sat_h, hmax / jnp.sqrt(jnp.where(sat_h, h2, 1.0)), 1.0)
    ax, ay = a[0] * sc, a[1] * sc
    sat = sat_z | sat_h
    lim = jnp.stack([c.i_lim_h, c.i_lim_h, c.i_lim_z])
    integ = jnp.where(sat, integ, _clamp(integ + e * dt, lim))
    d2 = jnp.stack([ax, ay, fz]) / jnp.sqrt(ax * ax + ay * ay + fz * fz)
    cy, sy = (jnp.cos(sp[9]), jnp.sin(sp[9])) if yaw_cs is None else yaw_cs
    b2 = jnp.stack([-d2[2] * sy, d2[2] * cy, d2[0] * sy - d2[1] * cy])
    d1 = b2 / jnp.sqrt(jnp.sum(b2 * b2))
    d0 = jnp.cross(d1, d2)
    R = rotation(quat)                                   # columns r0 r1 r2
    r0, r1, r2 = R[:, 0], R[:, 1], R[:, 2]
    er = 0.5 * jnp.stack([d2 @ r1 - d1 @ r2, d0 @ r2 - d2 @ r0, d1 @ r0 - d0 @ r1])
    J = c.J
    kr, ka = c.k_rate, c.k_att
    tx = J[0] * kr * (-ka * er[0] - w[0]) + (J[2] - J[1]) * w[1] * w[2]
    ty = J[1] * kr * (-ka * er[1] - w[1]) + (J[0] - J[2]) * w[2] * w[0]
    tz = J[2] * c.k_yaw_rate * (-c.k_yaw * er[2] - w[2]) + (J[1] - J[0]) * w[0] * w[1]
    T = jnp.maximum(0.0, c.mass * (ax * r2[0] + ay * r2[1] + fz * r2[2]))
    return (T, tx, ty, tz), integ


def rotation(quat):
    """The rotation matrix of a unit quaternion (w, x, y, z)."""
    qw, qx, qy, qz = quat[0], quat[1], quat[2], quat[3]
    xx, yy, zz, xy, xz, yz = qx * qx, qy * qy, qz * qz, qx * qy, qx * qz, qy * qz
    wx, wy, wz = qw * qx, qw * qy, qw * qz
    return jnp.stack([
        jnp.stack([1 - 2 * (yy + zz), 2 * (xy - wz), 2 * (xz + wy)]),
        jnp.stack([2 * (xy + wz), 1 - 2 * (xx + zz), 2 * (yz - wx)]),
        jnp.stack([2 * (xz - wy), 2 * (yz + wx), 1 - 2 * (xx + yy)])])


def mix(B, fmax, T, tx, ty, tz):
    """``CascadedController._mix``: the allocation, and when a rotor saturates,
    roll/pitch first (moving the collective if it can), then yaw scaled."""
    f = allocate(B, T, tx, ty, tz)
    return jnp.where(fits(f, fmax), f, saturated(B, fmax, T, tx, ty, tz))


def allocate(B, T, tx, ty, tz):
    """The mixer's allocation (every rotor within its range: the thrusts)."""
    return B[:, 0] * T + B[:, 1] * tx + B[:, 2] * ty + B[:, 3] * tz


def fits(f, fmax):
    """Whether the allocation ``f`` keeps every rotor within [0, fmax]."""
    return (jnp.min(f) >= 0.0) & (jnp.max(f) <= fmax)


def saturated(B, fmax, T, tx, ty, tz):
    """The mixer where a rotor saturates: roll/pitch first, then yaw scaled."""
    rp = B[:, 1] * tx + B[:, 2] * ty
    yw = B[:, 3] * tz
    lo, hi = jnp.min(rp), jnp.max(rp)
    b0 = B[0, 0] * T
    span_ok = hi - lo <= fmax
    b0 = jnp.where(span_ok, jnp.minimum(jnp.maximum(b0, -lo), fmax - hi),
                   0.5 * fmax - 0.5 * (hi + lo))
    s_rp = jnp.where(span_ok, 1.0, fmax / jnp.where(span_ok, 1.0, hi - lo))
    g = b0 + s_rp * rp
    ysafe = jnp.where(yw == 0.0, 1.0, yw)
    lim = jnp.where(yw > 0.0, jnp.maximum(0.0, (fmax - g) / ysafe),
                    jnp.where(yw < 0.0, jnp.maximum(0.0, -g / ysafe), 1.0))
    s_y = jnp.minimum(1.0, jnp.min(lim))
    return jnp.clip(g + s_y * yw, 0.0, fmax)
