"""What the batched (MJX) backend flies, and each variant's numbers.

``check(mission)`` raises a ``ConfigError`` naming whatever the batched path
does not fly (it stays per flight: ``backend="process"``): camera / ML tasks,
pilots other than Hover, Waypoints and ZigZag, a world, flying on estimates,
user components or probes, a dataset, energy components other than the
built-in ones. ``variant(mission)`` turns one resolved variant into plain
numbers (numpy), read from the core's own objects: the controller's gains from
``CascadedController``, the energy coefficients from the bound ``Meter``, the
battery circuit from the blueprint, the MuJoCo model from ``build_spec``. No
JAX here.
"""

from __future__ import annotations

import math

import numpy as np

from ...airframe.model import build_spec
from ...airframe.rotor_drag import h_coefficient, hubs
from ...control.controller import CascadedController
from ...control.pilots import Hover, Waypoints, ZigZag
from ...energy.components import Constant, RadioLinear, RadioStates, SoC
from ...energy.factory import flight_energy_model
from ...energy.model import Meter
from ...energy.rotors import HoverPower, Motors
from ...errors import ConfigError
from ...mission.book import book_period
from ...mission.plan import resolve, seed_sequence
from ...ml.scheduler import memory_utilization
from ...physics import G

PILOTS = (Hover, Waypoints, ZigZag)
ENERGY_KINDS = (Motors, Constant, SoC, RadioLinear, RadioStates, HoverPower)
#: end codes of the batched flight, in the order of ``END_REASONS``
END_REASONS = (None, "landed", "battery_depleted", "time", "time_cap", "crashed", "diverged")


def _refuse(what: str, value, why: str) -> ConfigError:
    return ConfigError(f"sweep: backend='mjx' cannot fly {what} = {value!r} ({why}); it flies "
                       f"Hover, Waypoints and ZigZag missions without tasks, worlds or user "
                       f"components; allowed here: backend='process' (per flight)")


def check(m) -> None:
    """ConfigError naming the first part of mission ``m`` the batched path does not fly."""
    if m.tasks:
        raise ConfigError(f"sweep: backend='mjx' cannot fly tasks = "
                          f"{[getattr(t, 'name', t) for t in m.tasks]!r} (camera and ML tasks "
                          f"stay per flight); allowed with tasks: backend='process'")
    if type(m.pilot) not in PILOTS:
        raise _refuse("pilot", m.pilot, f"{type(m.pilot).__name__} has no batched version")
    if m.world is not None:
        raise _refuse("world", m.world, "scenery stays per flight")
    if m.fly_on != "truth":
        raise _refuse("fly_on", m.fly_on, "the navigation estimate reads simulated sensors")
    if m.components:
        raise _refuse("components", m.components, "user components run Python every tick")
    custom = [p.name for p in m.probes if not getattr(p, "builtin", False)]
    if custom:
        raise _refuse("probes", custom, "user probes run Python on the flight")
    if m.dataset_dir is not None:
        raise _refuse("dataset_dir", str(m.dataset_dir), "recording a dataset renders frames")
    if m.max_wall_s is not None:
        raise _refuse("max_wall_s", m.max_wall_s, "a per-flight host-time guard")
    plan = resolve(m)
    model = flight_energy_model(m.drone.energy, extra_sensors=list(m.drone.extra_sensors)
                                + list(m.sensors), device=plan.onboard_device,
                                blueprint_device=m.drone.device)
    for path, comp in model.leaves():
        if type(comp) not in ENERGY_KINDS:
            raise _refuse(f"energy component {path!r}", comp, "a user energy component has no "
                          "batched version")


def _energy(meter) -> tuple[tuple, dict]:
    """(structure, numbers) of the energy model's leaves: one power per leaf."""
    kinds, tops, num = [], [], {"const_w": [], "radio": [], "states": []}
    motors = None
    for path, comp in meter.model.leaves():
        kinds.append(type(comp).__name__)
        tops.append(path.split(".", 1)[0])
        if isinstance(comp, Motors):
            motors = comp
            num["const_w"].append(0.0)
        elif isinstance(comp, HoverPower):
            num["const_w"].append(comp._p)              # airborne only (energy.py)
        elif isinstance(comp, SoC):
            num["const_w"].append(comp.idle_w)          # no tasks: never busy
        elif isinstance(comp, Constant):
            num["const_w"].append(comp.power_w)
        elif isinstance(comp, RadioLinear):
            num["const_w"].append(comp.idle_w)
            num["radio"].append([comp.tx_uj_per_byte, comp.tx_uj_per_packet,
                                 comp.rx_uj_per_byte, comp.rx_uj_per_packet])
        else:                                           # RadioStates
            num["const_w"].append(0.0)
            num["states"].append([comp.tx_w, comp.rx_w, comp.idle_w, comp.bitrate_bps])
    for key in ("radio", "states"):
        num[key] = np.asarray(num[key] or np.zeros((0, 4)), dtype=float).reshape(-1, 4)
    num["const_w"] = np.asarray(num["const_w"], dtype=float)
    if motors is not None:
        num.update(m_inv2rhoA=motors._inv2rhoA, m_c0=motors._c0, m_R=motors._R,
                   m_D=motors._D, m_L2=motors._L2,
                   m_inv_kf=motors._inv_kf, m_inv_eta=motors._inv_eta, m_hk=motors._hk,
                   m_kappa=motors.induced_power_factor, m_wake=motors.wake_interference,
                   m_dirs=np.asarray(motors._dirs, dtype=float),
                   m_vi0=np.asarray(motors._vi, dtype=float),
                   # the DC motor model (datasheet blueprints), else a constant efficiency
                   m_model=motors._kv is not None, m_esc=motors.esc_efficiency,
                   m_kv=motors._kv or 1.0, m_rm=motors.motor_rm_ohm or 0.0,
                   m_i0=motors.motor_i0_a or 0.0,
                   m_inv_w0=1.0 / motors.motor_i0_rad_s if motors.motor_i0_rad_s else 0.0)
    return (tuple(kinds), tuple(tops)), num


def _controller(c: CascadedController) -> dict:
    return {"mass": c.mass, "J": np.asarray(c.J, dtype=float), "fmax": c.fmax,
            "k_rate": c.k_rate, "k_att": c.k_att, "k_yaw_rate": c.k_yaw_rate, "k_yaw": c.k_yaw,
            "k_vel": c.k_vel, "k_vel_i": c.k_vel_i, "k_pos": c.k_pos, "tan_tilt": c.tan_tilt,
            "a_up": c.a_up, "a_down": c.a_down, "i_lim_h": c.i_lim_h, "i_lim_z": c.i_lim_z,
            "kd_h": c.kd_h, "kd_v": c.kd_v, "B": np.asarray(c.B, dtype=float)}


def _pilot(p) -> tuple[tuple, dict]:
    if isinstance(p, Waypoints):
        pts = np.asarray(p.points, dtype=float)
        return (("waypoints", len(pts), bool(p.loop)),
                {"points": pts, "speed": p.speed, "yaw": p.yaw, "duration": math.inf,
                 "return_speed": p.speed})
    return (("hover",), {"points": np.zeros((1, 3)), "speed": 0.0, "yaw": p.yaw,
                         "duration": math.inf if p.duration is None else p.duration,
                         "return_speed": getattr(p, "speed", 5.0)})


def _wind(plan) -> dict:
    w = plan.wind
    if w is None:
        return {"w_mean": np.zeros(3), "w_active": False, "w_gust_std": -1.0, "w_gust_tau": -1.0,
                "w_sigma_w20": 0.0, "w_carry": 1.0}
    return {"w_mean": np.asarray(w.mean, dtype=float), "w_active": bool(w.turbulent),
            "w_gust_std": -1.0 if w.gust_std is None else w.gust_std,
            "w_gust_tau": -1.0 if w.gust_tau_s is None else w.gust_tau_s,
            "w_sigma_w20": w.sigma_w20, "w_carry": w.carry_mps}


def variant(m) -> tuple[tuple, dict, object]:
    """(structure key, numbers, MuJoCo model) of one variant mission ``m``: variants
    with the same key fly in one batch."""
    plan = resolve(m)
    drone, rho = plan.drone, plan.atmosphere.density
    spec = build_spec(drone, None, physics_dt=plan.physics_dt, rho=rho)
    aero = spec.geom("aero")
    sizes, c_blunt = np.asarray(aero.size, dtype=float), float(aero.fluid_coefs[0])
    spec.option.density = 0.0           # MJX has only the inertia-box fluid model: drag is ours
    model = spec.compile()
    ctrl = CascadedController(drone, plan.ctrl_dt, rho=rho)
    meter = Meter(flight_energy_model(
        drone.energy, extra_sensors=list(drone.extra_sensors) + list(plan.sensors),
        device=plan.onboard_device, blueprint_device=drone.device), drone, rho=rho)
    e_key, e_num = _energy(meter)
    p_key, p_num = _pilot(plan.pilot)
    tw = drone.thrust_to_weight_at(rho)
    bat, circ = drone.battery, meter.battery
    num = {**_controller(ctrl), **e_num, **p_num, **_wind(plan),
           "accel": min(2.5, 0.25 * (tw - 1.0) * G, 1.5 * ctrl.k_vel),
           "altitude": float(plan.pilot.altitude), "climb_speed": plan.climb_speed,
           "descent_speed": plan.descent_speed, "return_home": plan.return_home,
           "rho": rho, "aero_size": sizes, "aero_c": c_blunt,
           # rotor drag (airframe/rotor_drag.py RotorDrag; blade_drag 0: none)
           "h_c": h_coefficient(drone.rotor.blade_drag, drone.rotor.diameter_m,
                                drone.rotor.thrust_coeff, rho),
           "h_hubs": np.asarray(hubs(drone), dtype=float),
           "e_usable": bat.energy_j, "reserve_j": bat.reserve_fraction * bat.energy_j,
           "b_lipo": circ.chemistry == "lipo", "b_cells": float(circ.cells), "b_qc": circ.q_c,
           "b_rmid": circ.r_mid, "b_vcut": circ.v_cut, "b_v0": circ.voltage_v,
           "hb_period": drone.radio.heartbeat_period_s, "hb_bytes": float(drone.radio.heartbeat_bytes),
           "t_end": plan.t_end, "timed": not isinstance(plan.until, str),
           "use_reserve": plan.use_reserve, "energy_period": 1.0 / plan.energy_hz,
           "mem_utilization": memory_utilization((), plan.onboard_device)}
    key = (plan.substeps, plan.physics_dt, plan.ctrl_dt, book_period(plan.ctrl_dt),
           drone.airframe.rotor_count, e_key, p_key, model.nq, model.nv, model.ngeom, model.nu)
    return key, num, model


def wind_rng(m) -> np.random.Generator:
    """The wind's random stream of variant ``m``: the core's (same seed, same gusts)."""
    return np.random.default_rng(seed_sequence(m.seed, "wind"))
