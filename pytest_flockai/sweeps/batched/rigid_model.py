"""The numbers of a drone's compiled MuJoCo model that the free-flight step
(``rigid.py``) needs, and whether it can fly that model at all (numpy only: the
sweep runner checks a mission before JAX is loaded)."""

from __future__ import annotations

from typing import NamedTuple

import mujoco
import numpy as np

from ...errors import ConfigError

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


class RigidData(NamedTuple):
    """The state: MuJoCo's ``time``, ``qpos`` (x y z qw qx qy qz), ``qvel`` (world linear,
    body angular), ``act`` (rotor thrusts), and whether the box touched the ground."""

    time: float
    qpos: np.ndarray
    qvel: np.ndarray
    act: np.ndarray
    contact: bool


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
