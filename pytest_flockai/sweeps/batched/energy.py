"""Body drag, Dryden wind, the energy integrator (motors, computer, radio,
battery circuit) and the flight book in ``jax.numpy``, for one variant.

The branch-free twins of ``airframe/mjspec.py``'s fluid ellipsoid (MuJoCo's
blunt drag, which MJX lacks: MJX implements only the inertia-box fluid model),
``world/wind.py`` (``WindSampler``), ``energy/components.py`` (``Constant``,
``SoC``, ``RadioLinear``, ``RadioStates``),
``energy/rotors.py`` (``Motors``, ``HoverPower``),
``energy/battery.py`` (``Circuit.draw``), ``energy/integrator.py``,
``comm/traffic.py`` (``Heartbeats``) and ``mission/book.py``.
"""

from __future__ import annotations

import math

import jax.numpy as jnp

from ...clock import CLOCK_EPS
from ...comm.traffic import ACK_BYTES
from ...control.stages import LANDING, PILOT, TAKEOFF
from ...energy.battery import CUTOFF_HOLD_S, ocv_liion, ocv_lipo, resistance_shape, terminal_current
from ...energy.rotors import VRS_K, wake_immersion
from ...mission.book import ACCEL_SMOOTHING_S, ACCEL_THRESHOLD, HOVER_SPEED
from ...world.wind import gust_intensities, ou_coefficients
from .control import rotation

MINVAL = 1e-15          # mjMINVAL: MuJoCo's guard in the projected-area quotient


def drag(a, quat, vel, wind):
    """World-frame force of MuJoCo's ellipsoid blunt drag (``fluid_coefs[0]``; the
    other coefficients are 0 and the air has no viscosity), as MuJoCo's
    ``mj_viscousForces`` computes it: in the ellipsoid's frame f = -rho C A_proj |v| v,
    A_proj = pi sqrt(sum (s_j s_k)^4 v_i^2 / sum (s_j s_k)^2 v_i^2) (s the semi-axes,
    v the velocity relative to the wind; pi s_j s_k along each axis)."""
    R = rotation(quat)
    lv = R.T @ (vel - wind)
    s0, s1, s2 = a.size[0], a.size[1], a.size[2]
    a2 = jnp.stack([(s1 * s2) ** 2, (s2 * s0) ** 2, (s0 * s1) ** 2])
    v2 = lv * lv
    area = jnp.pi * jnp.sqrt(jnp.sum(a2 * a2 * v2) / jnp.maximum(MINVAL, jnp.sum(a2 * v2)))
    return R @ (-a.rho * jnp.sqrt(jnp.sum(v2)) * area * a.c_blunt * lv)


def rotor_drag(a, quat, qvel, wind, act):
    """World-frame (force, torque about the CoM) of every rotor's H-force, as
    ``airframe.rotor_drag.RotorDrag.step``: per hub, -c sqrt(T) times the in-plane part of
    the air-relative velocity plus omega x r (body frame), summed and rotated to the world."""
    R = rotation(quat)
    b = R.T @ (qvel[:3] - wind)
    wx, wy, wz = qvel[3], qvel[4], qvel[5]               # free joint: body-frame rates
    x, y, h = a.h_hubs[:, 0], a.h_hubs[:, 1], a.h_hubs[:, 2]
    on = act > 0.0
    k = jnp.where(on, -a.h_c * jnp.sqrt(jnp.where(on, act, 0.0)), 0.0)
    hx = k * (b[0] + wy * h - wz * y)
    hy = k * (b[1] + wz * x - wx * h)
    f = jnp.stack([jnp.sum(hx), jnp.sum(hy), jnp.zeros_like(b[0])])
    tq = jnp.stack([-jnp.sum(h * hy), jnp.sum(h * hx), jnp.sum(x * hy - y * hx)])
    return R @ f, R @ tq


def wind_step(w, s, h, noise, dt):
    """``WindSampler.step(h)`` (``w = Wind.batch_params()``): (air velocity, new wind
    state); the intensities and the OU coefficients are the core's own formulas."""
    coef = jnp.stack(ou_coefficients(dt, *gust_intensities(h, w.sigma_w20, w.gust_std,
                                                            w.gust_tau_s, w.carry_mps, jnp), jnp))
    redo = jnp.isnan(s["w_h"]) | (jnp.abs(h - s["w_h"]) > 0.5)
    coef = jnp.where(redo, coef, s["w_coef"])
    g = s["w_g"]
    g = jnp.stack([coef[0] * g[0] + coef[1] * noise[0], coef[0] * g[1] + coef[1] * noise[1],
                   coef[2] * g[2] + coef[3] * noise[2]])
    act = w.active
    return (jnp.where(act, w.mean + g, w.mean),
            {"w_g": jnp.where(act, g, s["w_g"]), "w_coef": jnp.where(act, coef, s["w_coef"]),
             "w_h": jnp.where(act & redo, h, s["w_h"])})


def _descent_inflow(vg, vax, vpar2, vh):
    x = vax / jnp.where(vh > 0.0, vh, 1.0)
    k1, k2, k3, k4 = VRS_K
    v_emp = vh * (1.0 + x * (k1 + x * (k2 + x * (k3 + x * k4))))
    w = vax * vax / jnp.maximum(vax * vax + vpar2, 1e-300)
    v = jnp.maximum(w * v_emp + (1.0 - w) * vg, vg)
    return jnp.where((vh <= 0.0) | (x < -2.0), vg, v)


def motors(mp, thrust, vrel, vi):
    """``Motors.power_parts`` summed: (electrical power, new induced-velocity state)."""
    vx, vy, vax = vrel[0], vrel[1], vrel[2]
    vpar2 = vx * vx + vy * vy
    vpar = jnp.sqrt(vpar2)
    on = thrust > 1e-9
    T = jnp.where(on, thrust, 1.0)
    vh2 = T * mp.inv2rhoA
    v = jnp.where(vi <= 0.0, jnp.sqrt(vh2), vi)
    for _ in range(2):
        s = vax + v
        root = jnp.sqrt(vpar2 + s * s)
        df = jnp.where(root > 1e-9, root + v * s / jnp.where(root > 1e-9, root, 1.0), 1.0)
        v = jnp.maximum(0.0, v - (v * root - vh2) / df)
    vi = jnp.where(on, v, vi)
    v = jnp.where(vax < 0.0, _descent_inflow(v, vax, vpar2, jnp.sqrt(vh2)), v)
    induced = jnp.sum(jnp.where(on, mp.kappa * T * v, 0.0))
    axial = jnp.sum(jnp.where(on, T * vax, 0.0))
    omega = jnp.sqrt(T * mp.inv_kf)
    mu = vpar / (omega * mp.R)
    p0h = mp.c0 * T * jnp.sqrt(T)
    # the H-force's work is paid through the tilt (energy/rotors.py, airframe/rotor_drag.py)
    wr = omega * mp.R
    p0 = jnp.maximum(p0h, p0h * (1.0 + 4.65 * mu * mu) - mp.hk * wr * wr * wr * mu * mu)
    profile = jnp.sum(jnp.where(on, p0, 0.0))
    wake_vi = jnp.sum(jnp.where(on, v, 0.0))
    n = thrust.shape[0]
    vps = jnp.where(vpar > 0.1, vpar, 1.0)
    vi_mean = wake_vi / n
    ws = jnp.maximum(0.0, -(mp.dirs[:, 0] * vx / vps + mp.dirs[:, 1] * vy / vps))
    tot = jnp.sum(ws)
    scale = mp.wake * vi_mean * (0.5 * n) / jnp.where(tot > 0.0, tot, 1.0)
    use = (mp.wake > 0.0) & (vpar > 0.1) & (wake_vi > 0.0) & (tot > 0.0)
    # the aft rotors' immersion in the fore wake: the core's own formula, on arrays
    extra = jnp.where(use, ws * thrust * scale * wake_immersion(
        mp.L2 * ws, vax + vi_mean, vpar, mp.D, jnp.maximum, jnp.minimum), 0.0)
    induced = induced + jnp.sum(extra)
    shaft = jnp.where(on, mp.kappa * T * v + T * vax + p0 + extra, 0.0)
    total = induced + profile + axial
    inv_eta = jnp.where(mp.model & (total >= 0.0) & (total > 1e-12),
                        _electrical(mp, shaft, jnp.where(on, omega, 0.0))
                        / (jnp.where(total > 1e-12, total, 1.0) * mp.esc), mp.inv_eta)
    axial = jnp.where(total < 0.0, -(induced + profile), axial)
    return (induced + profile + axial) * inv_eta, vi


def _electrical(mp, shaft, omega):
    """``Motors._electrical``: the DC motor model's power at each rotor's operating point."""
    on = omega > 0.0
    om = jnp.where(on, omega, 1.0)
    q = jnp.where(shaft > 0.0, shaft / om, 0.0)
    i_nl = mp.i0 * jnp.sqrt(om * mp.inv_w0)
    cur = q * mp.kv + i_nl
    return jnp.sum(jnp.where(on, q * om + i_nl * om / mp.kv + cur * cur * mp.rm, 0.0))


def battery(b, s, power, dt):
    """``Circuit.draw(power, dt)`` (``b = Circuit.batch_params()``): (I^2 R loss, new
    battery state); the voltage, resistance and current are the core's own formulas."""
    soc = s["b_soc"]
    e = b.cells * jnp.where(b.lipo, ocv_lipo(soc, jnp), ocv_liion(soc, jnp))
    r = b.r_mid * resistance_shape(soc, jnp)
    i, over = terminal_current(e, r, power, jnp)
    v = e - i * r
    low = (i > 0.0) & (v < b.v_cut)
    below = jnp.where(low, s["b_below"] + dt, 0.0)
    cut = s["b_cut"] | over | (low & (below >= CUTOFF_HOLD_S - 1e-9))
    return i * i * r, {"b_soc": soc - i * dt / b.q_c, "b_below": below, "b_cut": cut,
                       "b_v": v, "b_vmin": jnp.minimum(s["b_vmin"], v)}


def leaf_powers(p, s, thrust, vrel, airborne, edt, kinds):
    """The power of every leaf of the energy model (W) and the new motor state."""
    n_hb = s["hb_pending"]
    tx_b, rx_b = n_hb * p.mission.hb_bytes, n_hb * ACK_BYTES
    safe = jnp.where(edt > 0.0, edt, 1.0)
    out, vi, r_i, s_i = [], s["vi"], 0, 0
    for k, kind in enumerate(kinds):
        base = p.energy.const_w[k]
        if kind == "Motors":
            pw, vi = motors(p.motors, thrust, vrel, s["vi"])
        elif kind == "HoverPower":
            pw = jnp.where(airborne, base, 0.0)
        elif kind == "RadioLinear":
            c = p.energy.radio[r_i]
            r_i += 1
            pw = base + jnp.where(edt > 0.0, (c[0] * tx_b + c[1] * n_hb + c[2] * rx_b
                                              + c[3] * n_hb) * 1e-6 / safe, 0.0)
        elif kind == "RadioStates":
            c = p.energy.states[s_i]
            s_i += 1
            t_tx, t_rx = tx_b * 8.0 / c[3], rx_b * 8.0 / c[3]
            idle = jnp.maximum(0.0, edt - t_tx - t_rx)
            pw = jnp.where(edt > 0.0, (c[2] * idle + c[0] * t_tx + c[1] * t_rx) / safe, c[2])
        else:
            pw = base
        out.append(pw)
    return jnp.stack(out), vi


def integrate(p, s, t, thrust, vrel, airborne, kinds):
    """One energy interval (t_e, t] charged (``EnergyIntegrator.step`` / ``finish``)."""
    edt = t - s["t_e"]
    pw, vi = leaf_powers(p, s, thrust, vrel, airborne, edt, kinds)
    total = jnp.sum(pw)
    loss, bat = battery(p.battery, s, total, edt)
    energy = s["energy_j"] + (total + loss) * edt
    return {**s, **bat, "vi": vi, "e_leaf": s["e_leaf"] + pw * edt, "loss_j": s["loss_j"] + loss * edt,
            "energy_j": energy, "t_e": t, "hb_drained": s["hb_drained"] + s["hb_pending"],
            "hb_pending": jnp.zeros_like(s["hb_pending"])}


def book(p, s, t, q, v, speed, period, every_tick):
    """``FlightBook.step``: phases in whole ticks, distance, top speed, tracking error."""
    bdt = t - s["t_book"]
    a = math.exp(-period / ACCEL_SMOOTHING_S)
    dv = v[:3] - s["pv"]
    acc = jnp.where(bdt > 0.0, a * s["acc"] + (1.0 - a) * jnp.sqrt(jnp.sum(dv * dv))
                    / jnp.where(bdt > 0.0, bdt, 1.0), s["acc"])
    stage, air = s["stage"], s["airborne"]
    phase = jnp.where(stage == TAKEOFF, 0, jnp.where(stage == LANDING, 4, jnp.where(
        speed < HOVER_SPEED, 1, jnp.where(acc > ACCEL_THRESHOLD, 3, 2))))
    err = jnp.sqrt(jnp.sum((q[:3] - s["sp"][:3]) ** 2))
    out = {"t_book": t, "pv": v[:3], "acc": jnp.where(air, acc, s["acc"]),
           "ticks": s["ticks"] + jnp.where(air, jnp.eye(6, dtype=s["ticks"].dtype)[phase], 0),
           "dist": s["dist"] + jnp.where(air, speed * period, 0.0),
           "vmax": jnp.where(air, jnp.maximum(s["vmax"], speed), s["vmax"]),
           "terr": jnp.where(air & (stage == PILOT), jnp.maximum(s["terr"], err), s["terr"]),
           "b_next": s["b_next"] + (0.0 if every_tick else period)}
    return out


def due(t, t_next):
    return t >= t_next - CLOCK_EPS
