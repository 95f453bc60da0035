"""What the batched backends (``jax``, ``mjx``) fly, and each variant's numbers.

``check(mission)`` raises a ``ConfigError`` naming whatever the batched path
does not fly (it stays per flight: ``backend="process"``): camera / ML tasks,
pilots other than Hover, Waypoints and ZigZag, a world, flying on estimates,
user components or probes, a dataset, energy components other than the
built-in ones. ``variant(mission)`` turns one resolved variant into typed
numbers (``VariantParams``, NamedTuples of numpy values), exported by the core's
own objects built by the flight's own factories (``mission/parts.py``): the
controller's ``batch_params()``, the bound motors' and battery circuit's, the
wind's, and the MuJoCo model from ``build_spec``. No JAX here.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ...airframe.mjspec import build_spec
from ...airframe.rotor_drag import h_coefficient, hubs
from ...control.controller import ControllerParams
from ...control.pilots import Hover, Waypoints, ZigZag
from ...energy.battery import BatteryParams
from ...energy.components import Constant, RadioLinear, RadioStates, SoC
from ...energy.rotors import HoverPower, MotorParams, Motors
from ...errors import ConfigError
from ...mission import parts
from ...mission.book import book_period
from ...mission.plan import resolve, seed_sequence
from ...ml.scheduler import memory_utilization
from ...world.wind import WindParams
from .rigid_model import FreeBody, free_body, free_body_of, unsupported

PILOTS = (Hover, Waypoints, ZigZag)
ENERGY_KINDS = (Motors, Constant, SoC, RadioLinear, RadioStates, HoverPower)
#: end codes of the batched flight, in the order of ``END_REASONS``
END_REASONS = (None, "landed", "battery_depleted", "time", "time_cap", "crashed", "diverged")


def _refuse(what: str, value, why: str, backend: str = "jax") -> ConfigError:
    return ConfigError(f"sweep: backend={backend!r} cannot fly {what} = {value!r} ({why}); it "
                       f"flies Hover, Waypoints and ZigZag missions without tasks, policies, "
                       f"worlds or user components; allowed here: backend='process' (per "
                       f"flight) or 'auto' (chooses it)")


def check(m, backend: str = "jax") -> None:
    """ConfigError naming the first part of mission ``m`` the batched path (``backend``:
    "jax" or "mjx", named in the message) does not fly: the batch never flies a mission
    other than the one asked (a policy ignored would change the verdict)."""
    if m.tasks:
        raise _refuse("tasks", [getattr(t, "name", t) for t in m.tasks],
                      "camera and ML tasks stay per flight", backend)
    if getattr(m, "policies", ()):
        raise _refuse("policies", [getattr(p, "name", p) for p in m.policies],
                      "a policy decides in Python during the flight", backend)
    if getattr(m, "actors", ()):
        raise _refuse("actors", len(m.actors), "moving people and cars stay per flight", backend)
    if type(m.pilot) not in PILOTS:
        raise _refuse("pilot", m.pilot, f"{type(m.pilot).__name__} has no batched version", backend)
    if m.world is not None:
        raise _refuse("world", m.world, "scenery stays per flight", backend)
    if m.fly_on != "truth":
        raise _refuse("fly_on", m.fly_on, "the navigation estimate reads simulated sensors", backend)
    if m.components:
        raise _refuse("components", m.components, "user components run Python every tick", backend)
    custom = [p.name for p in m.probes if not getattr(p, "builtin", False)]
    if custom:
        raise _refuse("probes", custom, "user probes run Python on the flight", backend)
    if m.dataset_dir is not None:
        raise _refuse("dataset_dir", str(m.dataset_dir), "recording a dataset renders frames", backend)
    if m.max_wall_s is not None:
        raise _refuse("max_wall_s", m.max_wall_s, "a per-flight host-time guard", backend)
    for path, comp in parts.energy_model(resolve(m)).leaves():
        if type(comp) not in ENERGY_KINDS:
            raise _refuse(f"energy component {path!r}", comp, "a user energy component has no "
                          "batched version", backend)


class EnergyLeaves(NamedTuple):
    """Per leaf of the energy model: its constant power (W; 0 for motors and radio states),
    the ``RadioLinear`` coefficients (uJ per byte / packet, tx then rx) and the
    ``RadioStates`` powers (tx, rx, idle W, bit rate), in leaf order."""

    const_w: np.ndarray
    radio: np.ndarray
    states: np.ndarray


class PilotParams(NamedTuple):
    """A Hover's or a Waypoints' numbers (``points`` (k, 3): the waypoints)."""

    points: np.ndarray
    speed: float
    yaw: float
    duration: float
    return_speed: float
    altitude: float


class MissionParams(NamedTuple):
    """The plan's numbers: stages, clocks, end conditions, heartbeats."""

    accel: float
    climb_speed: float
    descent_speed: float
    return_home: bool
    t_end: float
    timed: bool
    use_reserve: bool
    energy_period: float
    e_usable: float
    reserve_j: float
    hb_period: float
    hb_bytes: float
    mem_utilization: float


class AeroParams(NamedTuple):
    """Air density, the fluid ellipsoid (semi-axes, blunt drag coefficient) and the rotors'
    H-force (coefficient, hubs (n, 3) in the body frame)."""

    rho: float
    size: np.ndarray
    c_blunt: float
    h_c: float
    h_hubs: np.ndarray


class VariantParams(NamedTuple):
    """One variant's numbers, grouped by the core object that exports them (a pytree of
    arrays: stacked over a batch, ``jax.vmap``-ed)."""

    ctrl: ControllerParams
    motors: MotorParams
    battery: BatteryParams
    wind: WindParams
    energy: EnergyLeaves
    pilot: PilotParams
    mission: MissionParams
    aero: AeroParams


def _no_motors(n: int) -> MotorParams:
    """Placeholder coefficients where the model has no ``Motors`` (never evaluated)."""
    return MotorParams(1.0, 0.0, 1.0, 1.0, 1.0, 0.0, 1.0, 0.0, np.zeros((n, 2)), np.zeros(n),
                       False, 1.0, 1.0, 0.0, 0.0, 0.0)


def _energy(meter, n: int) -> tuple[tuple, EnergyLeaves, MotorParams]:
    """(structure, leaves' numbers, motor coefficients) of the energy model."""
    kinds, tops, const, radio, states = [], [], [], [], []
    motors = _no_motors(n)
    for path, comp in meter.model.leaves():
        kinds.append(type(comp).__name__)
        tops.append(path.split(".", 1)[0])
        if isinstance(comp, Motors):
            motors = comp.batch_params()
            const.append(0.0)
        elif isinstance(comp, HoverPower):
            const.append(comp.airborne_power_w)          # airborne only (energy.py)
        elif isinstance(comp, SoC):
            const.append(comp.idle_w)                    # no tasks: never busy
        elif isinstance(comp, Constant):
            const.append(comp.power_w)
        elif isinstance(comp, RadioLinear):
            const.append(comp.idle_w)
            radio.append([comp.tx_uj_per_byte, comp.tx_uj_per_packet, comp.rx_uj_per_byte,
                          comp.rx_uj_per_packet])
        else:                                            # RadioStates
            const.append(0.0)
            states.append([comp.tx_w, comp.rx_w, comp.idle_w, comp.bitrate_bps])
    leaves = EnergyLeaves(np.asarray(const, dtype=float),
                          np.asarray(radio or np.zeros((0, 4)), dtype=float).reshape(-1, 4),
                          np.asarray(states or np.zeros((0, 4)), dtype=float).reshape(-1, 4))
    return (tuple(kinds), tuple(tops)), leaves, motors


def _pilot(p) -> tuple[tuple, PilotParams]:
    alt = float(p.altitude)
    if isinstance(p, Waypoints):
        pts = np.asarray(p.points, dtype=float)
        return (("waypoints", len(pts), bool(p.loop)),
                PilotParams(pts, p.speed, p.yaw, math.inf, p.speed, alt))
    return (("hover",), PilotParams(np.zeros((1, 3)), 0.0, p.yaw,
                                    math.inf if p.duration is None else p.duration,
                                    getattr(p, "speed", 5.0), alt))


def _wind(plan) -> WindParams:
    if plan.wind is None:
        return WindParams(np.zeros(3), False, -1.0, -1.0, 0.0, 1.0)
    return plan.wind.batch_params()


def _mission(plan, drone, meter, ctrl) -> MissionParams:
    bat = drone.battery
    return MissionParams(
        accel=parts.trajectory_accel(plan, ctrl),
        climb_speed=plan.climb_speed, descent_speed=plan.descent_speed,
        return_home=plan.return_home, t_end=plan.t_end, timed=not isinstance(plan.until, str),
        use_reserve=plan.use_reserve, energy_period=1.0 / plan.energy_hz,
        e_usable=bat.energy_j, reserve_j=bat.reserve_fraction * bat.energy_j,
        hb_period=drone.radio.heartbeat_period_s, hb_bytes=float(drone.radio.heartbeat_bytes),
        mem_utilization=memory_utilization((), plan.onboard_device))


def variant(m, plan=None, physics: str = "mjx", derive: bool = True) -> tuple[tuple, VariantParams, object]:
    """(structure key, numbers, model) of one variant mission ``m`` (``plan``: its resolved
    plan, if the caller has it): variants with the same key fly in one batch. The model:
    the compiled MuJoCo model (``physics="mjx"``), or the ``FreeBody`` (``"jax"``), derived
    from the blueprint without compiling (``rigid_model.free_body``; key ending in
    ``("free", n)``) unless ``derive=False`` or it cannot, then from the compiled model."""
    plan = resolve(m) if plan is None else plan
    drone, rho = plan.drone, plan.atmosphere.density
    model = free_body(drone, plan.physics_dt, rho) if physics == "jax" and derive else None
    if model is not None:
        shape: tuple = ("free", len(model.rigid.tau))
        sizes, c_blunt = model.aero_size, model.c_blunt
    else:
        model, sizes, c_blunt = compiled(plan)
        shape = (model.nq, model.nv, model.ngeom, model.nu)
        if physics == "jax":
            model = free_body_of(model, sizes, c_blunt)
    ctrl = parts.controller(plan)
    meter = parts.meter(plan)
    e_key, leaves, motors = _energy(meter, drone.airframe.rotor_count)
    p_key, pilot = _pilot(plan.pilot)
    num = VariantParams(
        ctrl=ctrl.batch_params(), motors=motors, battery=meter.battery.batch_params(),
        wind=_wind(plan), energy=leaves, pilot=pilot, mission=_mission(plan, drone, meter, ctrl),
        # the fluid ellipsoid (airframe/mjspec.py) and the rotors' H-force
        # (airframe/rotor_drag.py RotorDrag; blade_drag 0: none)
        aero=AeroParams(rho=rho, size=sizes, c_blunt=c_blunt,
                        h_c=h_coefficient(drone.rotor.blade_drag, drone.rotor.diameter_m,
                                          drone.rotor.thrust_coeff, rho),
                        h_hubs=np.asarray(hubs(drone), dtype=float)))
    key = (plan.substeps, plan.physics_dt, plan.ctrl_dt, book_period(plan.ctrl_dt),
           drone.airframe.rotor_count, e_key, p_key, shape)
    return key, num, model


def compiled(plan) -> tuple:
    """(compiled MuJoCo model, fluid ellipsoid's semi-axes, blunt drag coefficient) of the
    plan's drone, MuJoCo's own fluid model off (MJX has only the inertia-box one: the body
    drag is ours)."""
    spec = build_spec(plan.drone, None, physics_dt=plan.physics_dt, rho=plan.atmosphere.density)
    aero = spec.geom("aero")
    sizes, c_blunt = np.asarray(aero.size, dtype=float), float(aero.fluid_coefs[0])
    spec.option.density = 0.0
    return spec.compile(), sizes, c_blunt


def compiled_body(m) -> FreeBody:
    """The ``FreeBody`` of mission ``m``'s drone read from its compiled MuJoCo model (the
    reference ``free_body`` is checked against)."""
    model, sizes, c_blunt = compiled(resolve(m))
    return free_body_of(model, sizes, c_blunt)


def free_flight_unsupported(m) -> str | None:
    """Why the free-flight body (``backend="jax"``) cannot fly mission ``m``'s drone (None:
    it can; then ``backend="mjx"`` is not needed)."""
    return unsupported(compiled(resolve(m))[0])


def wind_rng(m) -> np.random.Generator:
    """The wind's random stream of variant ``m``: the core's (same seed, same gusts)."""
    return np.random.default_rng(seed_sequence(m.seed, "wind"))
