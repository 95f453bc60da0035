"""The numbers of a drone's compiled MuJoCo model that the free-flight step
(``rigid.py``) needs, and whether it can fly that model at all (numpy only: the
sweep runner checks a mission before JAX is loaded)."""

from __future__ import annotations

from typing import Any, NamedTuple

import mujoco
import numpy as np

from ...airframe.mjspec import AERO_SCALE, drag_ellipsoid
from ...errors import ConfigError
from ...physics import RHO_SEA_LEVEL, G

_FREE, _BOX, _SITE = mujoco.mjtJoint.mjJNT_FREE, mujoco.mjtGeom.mjGEOM_BOX, mujoco.mjtTrn.mjTRN_SITE


class RigidModel(NamedTuple):
    """The numbers of one drone's MuJoCo model the free-flight step needs."""

    mass: float
    inertia: np.ndarray          # (3,) principal, body frame
    gravity: np.ndarray          # (3,)
    dt: float
    site: np.ndarray             # (n, 3) rotor sites, body frame
    gear: np.ndarray             # (n, 6) force (site z) and torque gears
    tau: np.ndarray              # (n,) rotor filter time constants
    fade: np.ndarray             # (n,) 1 - exp(-dt / tau): the exact filter's step
    ctrl_lo: np.ndarray
    ctrl_hi: np.ndarray
    half: np.ndarray             # (3,) collision box half sizes


class FreeBody(NamedTuple):
    """A variant's free body: its ``RigidModel``, the initial ``qpos`` (``qpos0``) and the
    body drag's fluid ellipsoid (semi-axes, blunt drag coefficient)."""

    rigid: RigidModel
    qpos0: np.ndarray
    aero_size: np.ndarray
    c_blunt: float


class RigidData(NamedTuple):
    """The state: MuJoCo's ``time``, ``qpos`` (x y z qw qx qy qz), ``qvel`` (world linear,
    body angular), ``act`` (rotor thrusts), and whether the box touched the ground."""

    # NumPy values when built here, JAX arrays (traced) inside the jitted step
    time: Any
    qpos: Any
    qvel: Any
    act: Any
    contact: Any


def unsupported(model) -> str | None:
    """Why the free-flight step cannot fly ``model`` (None: it can)."""
    if model.nbody != 2 or model.njnt != 1 or model.jnt_type[0] != _FREE:
        return "the model is not one body on a free joint"
    if np.any(model.body_ipos[1] != 0.0) or np.any(model.body_iquat[1] != [1.0, 0.0, 0.0, 0.0]):
        return "the centre of mass or the principal axes are off the body frame"
    if model.opt.integrator != mujoco.mjtIntegrator.mjINT_EULER or np.any(model.dof_damping) \
            or np.any(model.dof_armature):
        return "not the Euler integrator without damping and armature"
    if model.nu == 0 or np.any(model.actuator_trntype != _SITE) or np.any(
            model.actuator_dyntype != mujoco.mjtDyn.mjDYN_FILTEREXACT) or np.any(
            model.actuator_gaintype != mujoco.mjtGain.mjGAIN_FIXED) or np.any(
            model.actuator_biastype != mujoco.mjtBias.mjBIAS_NONE) or np.any(
            model.actuator_gainprm[:, 0] != 1.0) or np.any(model.actuator_actearly) or np.any(
            model.site_quat[model.actuator_trnid[:, 0]] != [1.0, 0.0, 0.0, 0.0]):
        return "the actuators are not the blueprint's filtered rotor thrusts"
    box = _colliders(model)
    if len(box) != 1 or model.opt.density != 0.0 or model.opt.viscosity != 0.0:
        return "not one collision geom, or MuJoCo's fluid forces are on"
    if model.geom_type[box[0]] != _BOX or np.any(model.geom_pos[box[0]] != 0.0) or np.any(
            model.geom_quat[box[0]] != [1.0, 0.0, 0.0, 0.0]):
        return "the collision geom is not a box centred on the body"
    return None


def _colliders(model) -> list[int]:
    return [g for g in range(model.ngeom) if model.geom_bodyid[g] == 1
            and (model.geom_contype[g] or model.geom_conaffinity[g])]


def model_of(model, check: bool = True) -> RigidModel:
    """The free-flight numbers of a compiled MuJoCo model (``ConfigError`` if unsupported;
    ``check=False``: a variant of a model already checked, same structure)."""
    why = unsupported(model) if check else None
    if why is not None:
        raise ConfigError(f"sweep: backend='jax' cannot fly this drone's MuJoCo model ({why}); "
                          f"allowed: backend='mjx' or 'process'")
    sites, box = model.actuator_trnid[:, 0], _colliders(model)
    tau = np.maximum(mujoco.mjMINVAL, np.array(model.actuator_dynprm[:, 0], dtype=float))
    return RigidModel(
        mass=float(model.body_mass[1]), inertia=np.array(model.body_inertia[1], dtype=float),
        gravity=np.array(model.opt.gravity, dtype=float), dt=float(model.opt.timestep),
        site=np.array(model.site_pos[sites], dtype=float),
        gear=np.array(model.actuator_gear, dtype=float),
        tau=tau, fade=1.0 - np.exp(-float(model.opt.timestep) / tau),
        ctrl_lo=np.where(model.actuator_ctrllimited, model.actuator_ctrlrange[:, 0], -np.inf),
        ctrl_hi=np.where(model.actuator_ctrllimited, model.actuator_ctrlrange[:, 1], np.inf),
        half=np.array(model.geom_size[box[0]], dtype=float))


def data_of(data) -> RigidData:
    """The free-flight state of an ``MjData`` (after ``mj_forward``)."""
    return RigidData(float(data.time), np.array(data.qpos, dtype=float),
                     np.array(data.qvel, dtype=float), np.array(data.act, dtype=float), False)


def free_body_of(model, aero_size, c_blunt: float, check: bool = True) -> FreeBody:
    """The ``FreeBody`` of a compiled MuJoCo model (``model_of``'s check)."""
    return FreeBody(model_of(model, check), np.array(model.qpos0, dtype=float),
                    np.asarray(aero_size, dtype=float), float(c_blunt))


def free_body(drone, physics_dt: float, rho: float) -> FreeBody | None:
    """The ``FreeBody`` of ``drone`` computed from its blueprint without building and
    compiling its MuJoCo model, with ``airframe/mjspec.py``'s formulas (``add_drone``:
    mass and inertia explicit at the body origin, one site per rotor on the hull's top,
    gear (0, 0, 1, 0, 0, -spin km/kf), filter time constant, thrust range [0, max thrust
    scaled with rho], hull box, fluid ellipsoid); MuJoCo's compile copies these numbers.
    The sweep checks the result against compiled members (``engine``) and compiles every
    variant where they differ. None where the compile would refuse the numbers (mass or
    inertia below ``mjMINVAL``, an inertia that breaks the triangle inequality, no
    thrust): the caller compiles, and the compile says what is wrong."""
    af, rotor = drone.airframe, drone.rotor
    mass, inertia = float(drone.mass_kg), np.array(af.inertia_kg_m2, dtype=float)
    fmax = rotor.max_thrust_n * rho / RHO_SEA_LEVEL
    if inertia.shape != (3,) or not (mass >= mujoco.mjMINVAL and np.all(inertia >= mujoco.mjMINVAL)
                                      and fmax > 0.0) or np.any(
            inertia[[0, 1, 2]] + inertia[[1, 2, 0]] < inertia[[2, 0, 1]]):
        return None
    L, W, H = af.body_size_m
    k = rotor.torque_coeff / rotor.thrust_coeff
    layout = drone.rotor_layout()
    n = len(layout)
    gear = np.zeros((n, 6))
    gear[:, 2] = 1.0
    gear[:, 5] = [-spin * k for _, _, spin in layout]
    tau = np.full(n, max(mujoco.mjMINVAL, float(rotor.time_constant_s)))
    dt = float(physics_dt)
    rigid = RigidModel(
        mass=mass, inertia=inertia, gravity=np.array([0.0, 0.0, -G]), dt=dt,
        site=np.array([[x, y, 0.5 * H] for x, y, _ in layout], dtype=float), gear=gear,
        tau=tau, fade=1.0 - np.exp(-dt / tau), ctrl_lo=np.zeros(n), ctrl_hi=np.full(n, fmax),
        half=np.array([0.5 * L, 0.5 * W, 0.5 * H], dtype=float))
    return FreeBody(rigid, np.array([0.0, 0.0, 0.5 * H + 1e-3, 1.0, 0.0, 0.0, 0.0]),
                    np.array([AERO_SCALE * r for r in drag_ellipsoid(af.drag_area_m2)]),
                    0.5 / AERO_SCALE ** 2)


def same_body(a: FreeBody, b: FreeBody, rtol: float = 1e-12) -> bool:
    """Whether two free bodies hold the same numbers (to ``rtol``, relative)."""
    la, lb = _leaves(a), _leaves(b)
    return len(la) == len(lb) and all(
        x.shape == y.shape and bool(np.all((x == y) | (np.abs(x - y) <= rtol * np.abs(y))))
        for x, y in zip(la, lb))


def _leaves(body: FreeBody) -> list[np.ndarray]:
    """The free body's numbers as flat float arrays (``same_body``)."""
    return [np.atleast_1d(np.asarray(x, dtype=float)) for x in (*body.rigid, *body[1:])]
