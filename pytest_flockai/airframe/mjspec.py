"""Compose the MuJoCo model of a drone (and its world) with ``mujoco.MjSpec``.

The drone is a free body with the blueprint's mass and inertia (payload added
at the centre), a collision box, and one site per rotor. Each rotor is a MuJoCo
actuator on its site: force along the rotor axis and reaction torque
``-spin * km/kf`` per newton about it, with first-order dynamics
(``mjDYN_FILTEREXACT``, time constant = motor time constant) and the control
clamped to [0, max thrust]. Motor lag and saturation therefore run inside
MuJoCo at the physics rate; Python only runs at the control rate. The lag is
applied to thrust rather than rotor speed (a first-order approximation).

Body drag is MuJoCo's ellipsoid fluid model, computed every physics step
against the air velocity (``opt.wind``, which the mission updates with the
gusts): a massless, non-colliding ellipsoid whose projected areas along the
body axes equal the blueprint's Cd*A, with only the blunt-drag coefficient
set. MuJoCo's blunt drag is rho * C * A_proj * |v| * v, so C = 0.5 gives
1/2 rho (Cd A) |v| v along each axis (checked in tests/mission/test_flight.py).
The ellipsoid model also adds added-mass forces, proportional to the
ellipsoid's volume: a drone is not an ellipsoidal hull, and at 10 m/s the
resulting Munk moment rivals the Mavic's control authority. Drag scales with
C * area and added mass with volume, so the ellipsoid is shrunk by
``AERO_SCALE`` and C raised by 1 / AERO_SCALE^2: same drag, added mass / 1000.
"""

from __future__ import annotations

import math

from .._mujoco import mujoco
from ..physics import RHO_SEA_LEVEL, G


def build_spec(drone, world=None, *, physics_dt: float, rho: float = RHO_SEA_LEVEL) -> mujoco.MjSpec:
    """The drone (and world) in air of density ``rho``: body drag and the rotors'
    maximum thrust (T = kf rho / rho_0 omega^2, kf given at sea level) scale with it."""
    spec = world_spec(drone.name, world, physics_dt=physics_dt, rho=rho)
    add_drone(spec, drone, rho=rho)
    return spec


def world_spec(name: str, world=None, *, physics_dt: float, rho: float = RHO_SEA_LEVEL) -> mujoco.MjSpec:
    """The physics options and the world (or the empty ground), no drone yet."""
    spec = mujoco.MjSpec()
    spec.modelname = name
    spec.option.timestep = physics_dt
    spec.option.gravity = [0.0, 0.0, -G]
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_EULER
    spec.option.density = rho
    spec.option.viscosity = 0.0
    (world if world is not None else _EMPTY).add_to_spec(spec)
    return spec


def add_drone(spec: mujoco.MjSpec, drone, *, rho: float = RHO_SEA_LEVEL, prefix: str = "",
              pos=(0.0, 0.0), visual: bool = True) -> None:
    """Add ``drone`` to ``spec`` standing at ``pos`` (x, y) on the ground: its body,
    joint, geoms, sites and actuators named with ``prefix`` (a fleet puts several
    drones in one model; a single flight uses no prefix). ``visual=False`` leaves
    out the arms and propellers: they neither collide nor carry mass (the inertia
    is explicit), only cameras and rays see them, and each costs MuJoCo time on
    every physics step (a fleet without cameras or rangefinders leaves them out)."""
    p = prefix
    af = drone.airframe
    L, W, H = af.body_size_m
    body = spec.worldbody.add_body(name=f"{p}drone", pos=[float(pos[0]), float(pos[1]), 0.5 * H + 1e-3])
    body.add_freejoint(name=f"{p}drone")
    body.explicitinertial = True
    body.mass = drone.mass_kg
    body.inertia = list(af.inertia_kg_m2)
    body.ipos = [0.0, 0.0, 0.0]
    body.add_geom(name=f"{p}hull", type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.5 * L, 0.5 * W, 0.5 * H],
                  rgba=[0.25, 0.25, 0.28, 1], friction=[1.0, 0.005, 0.0001])
    ax, ay, az = (AERO_SCALE * r for r in drag_ellipsoid(af.drag_area_m2))
    aero = body.add_geom(name=f"{p}aero", type=mujoco.mjtGeom.mjGEOM_ELLIPSOID, size=[ax, ay, az],
                         contype=0, conaffinity=0, group=3, mass=0.0, rgba=[0, 0, 0, 0])
    aero.fluid_ellipsoid = 1
    aero.fluid_coefs = [0.5 / AERO_SCALE ** 2, 0.0, 0.0, 0.0, 0.0]
    k = drone.rotor.torque_coeff / drone.rotor.thrust_coeff
    r_prop = 0.5 * drone.rotor.diameter_m
    fmax = drone.rotor.max_thrust_n * rho / RHO_SEA_LEVEL
    for i, (x, y, spin) in enumerate(drone.rotor_layout()):
        if visual:
            body.add_geom(name=f"{p}arm{i}", type=mujoco.mjtGeom.mjGEOM_CAPSULE,
                          fromto=[0, 0, 0, x, y, 0], size=[0.1 * H, 0, 0], contype=0,
                          conaffinity=0, rgba=[0.2, 0.2, 0.2, 1])
            body.add_geom(name=f"{p}prop{i}", type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                          pos=[x, y, 0.5 * H], size=[r_prop, 0.002, 0], contype=0, conaffinity=0,
                          rgba=[0.7, 0.7, 0.75, 0.5])
        body.add_site(name=f"{p}rotor{i}", pos=[x, y, 0.5 * H])
        act = spec.add_actuator(name=f"{p}rotor{i}", target=f"{p}rotor{i}",
                                trntype=mujoco.mjtTrn.mjTRN_SITE)
        act.gear = [0.0, 0.0, 1.0, 0.0, 0.0, -spin * k]
        act.dyntype = mujoco.mjtDyn.mjDYN_FILTEREXACT
        act.dynprm[0] = drone.rotor.time_constant_s
        act.gaintype = mujoco.mjtGain.mjGAIN_FIXED
        act.gainprm[0] = 1.0
        act.biastype = mujoco.mjtBias.mjBIAS_NONE
        act.ctrllimited = 1
        act.ctrlrange = [0.0, fmax]


AERO_SCALE = 0.1


def drag_ellipsoid(cda):
    """Semi-axes (a, b, c) whose projected areas pi*b*c, pi*a*c, pi*a*b equal CdA x, y, z."""
    cx, cy, cz = cda
    return (math.sqrt(cy * cz / (math.pi * cx)), math.sqrt(cx * cz / (math.pi * cy)),
            math.sqrt(cx * cy / (math.pi * cz)))


class _Empty:
    def add_to_spec(self, spec):
        spec.worldbody.add_geom(name="ground", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 1])


_EMPTY = _Empty()


def build_model(drone, world=None, *, physics_dt: float, rho: float = RHO_SEA_LEVEL) -> mujoco.MjModel:
    return build_spec(drone, world, physics_dt=physics_dt, rho=rho).compile()
