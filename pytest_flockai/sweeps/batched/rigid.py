"""A free-flying rigid body in ``jax.numpy``: MuJoCo's step for the flight model of a
blueprint (one body on a free joint, rotors as site actuators with a first-order
filter), without MuJoCo's general collision and constraint pipeline, which is what
MJX spends most of its CPU time on for a drone in open air.

``rigid_model.model_of`` reads the compiled MuJoCo model (mass, inertia, gravity, timestep, each
rotor's site, gear and filter time constant, the collision box); ``step`` is MuJoCo's
semi-implicit Euler step for that model (``mj_step`` with ``opt.integrator = Euler``):

- actuator force = act (gain 1, no bias) at each rotor site along the body z axis, and
  the gear's reaction torque about it; ``xfrc_applied`` (the body and rotor drag) at
  the centre of mass;
- qacc: a = F / m + g, dw/dt = I^-1 (tau - w x I w) (free joint, centre of mass at the
  body origin, principal axes along the body's: ``model_of`` checks both);
- act += (ctrl - act)(1 - exp(-dt / tau)) (``filterexact``; ctrl clamped to its range),
  qvel += dt qacc, position += dt v, quaternion rotated by the body rate (MuJoCo's
  ``mju_quatIntegrate``) and normalised, time += dt.

Ground contact is handled separately: the collision box against the plane z = 0. A
box corner below the ground is pushed back up to it, the downward velocity removed,
and while resting (not rising) the body neither slides nor turns (take-off from the
pad, touchdown). That is not MuJoCo's soft contact, which lets the box sink a
fraction of a millimetre and decelerates it over a few milliseconds: a touchdown is
seen a step or two earlier. Where contacts matter beyond that (a world with
obstacles), the batched path stays on MJX. Checked against C MuJoCo step by step in
``tests/sweeps/test_batched_twins.py``.
"""

from __future__ import annotations

import jax.numpy as jnp
import mujoco

from .rigid_model import RigidData, RigidModel, data_of, model_of, same_body, unsupported

__all__ = ["RigidData", "RigidModel", "data_of", "model_of", "same_body", "unsupported", "step", "ground", "up_z"]


def rotation(q):
    """Rotation matrix of the unit quaternion q = (w, x, y, z)."""
    w, x, y, z = q[0], q[1], q[2], q[3]
    return jnp.stack([
        jnp.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)]),
        jnp.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)]),
        jnp.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)])])


def _quat_integrate(q, w, dt):
    """``mju_quatIntegrate``: q times the rotation by the body rate w over dt, normalised."""
    n = jnp.sqrt(jnp.sum(w * w))
    ok = n > mujoco.mjMINVAL
    half = 0.5 * n * dt
    axis = w / jnp.where(ok, n, 1.0)
    r = jnp.where(ok, jnp.concatenate([jnp.cos(half)[None], jnp.sin(half) * axis]),
                  jnp.array([1.0, 0.0, 0.0, 0.0]))
    out = jnp.stack([
        q[0] * r[0] - q[1] * r[1] - q[2] * r[2] - q[3] * r[3],
        q[0] * r[1] + q[1] * r[0] + q[2] * r[3] - q[3] * r[2],
        q[0] * r[2] - q[1] * r[3] + q[2] * r[0] + q[3] * r[1],
        q[0] * r[3] + q[1] * r[2] - q[2] * r[1] + q[3] * r[0]])
    return out / jnp.sqrt(jnp.sum(out * out))


def step(m: RigidModel, d: RigidData, ctrl, xfrc) -> RigidData:
    """One ``mj_step`` (Euler) with ``ctrl`` (n,) and ``xfrc`` (6,): world force and torque
    at the centre of mass; then the ground."""
    q, v, act = d.qpos, d.qvel, d.act
    R = rotation(q[3:7])
    w = v[3:6]
    # generalized forces: rotor thrust along body z at each site, gear torques, xfrc
    f_body = jnp.stack([jnp.sum(m.gear[:, 0] * act), jnp.sum(m.gear[:, 1] * act),
                        jnp.sum(m.gear[:, 2] * act)])
    lever = jnp.cross(m.site, m.gear[:, :3] * act[:, None])
    t_body = jnp.sum(lever, axis=0) + jnp.sum(m.gear[:, 3:] * act[:, None], axis=0)
    f_world = R @ f_body + xfrc[:3]
    t_body = t_body + R.T @ xfrc[3:]
    lin = f_world / m.mass + m.gravity
    Iw = m.inertia * w
    ang = (t_body - jnp.cross(w, Iw)) / m.inertia
    ctrl = jnp.clip(ctrl, m.ctrl_lo, m.ctrl_hi)
    act = act + (ctrl - act) / m.tau * m.tau * m.fade
    v = v + m.dt * jnp.concatenate([lin, ang])
    pos = q[:3] + m.dt * v[:3]
    quat = _quat_integrate(q[3:7], v[3:6], m.dt)
    return ground(m, RigidData(d.time + m.dt, jnp.concatenate([pos, quat]), v, act, d.contact))


#: sliding friction of the drone's box on the ground: MuJoCo takes the larger of the two
#: geoms' (the floor's 1.0 in ``airframe/mjspec.py``, the box's MuJoCo default 1.0)
MU_GROUND = 1.0


def ground(m: RigidModel, d: RigidData) -> RigidData:
    """The collision box against the plane z = 0: a corner below it is pushed back up,
    the downward velocity removed; resting on it, the body does not turn, and slides
    with Coulomb friction: the horizontal velocity loses at most ``MU_GROUND`` times the
    vertical velocity the ground took away (a drone pushed along the pad by strong wind
    as it spools up slides, as on MuJoCo's contact)."""
    q, v = d.qpos, d.qvel
    w, x, y, z = q[3], q[4], q[5], q[6]
    r2 = jnp.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)])  # R[2]
    low = q[2] - jnp.sum(jnp.abs(r2) * m.half)
    touch = low <= 0.0
    rest = touch & (v[2] <= 0.0)
    z = jnp.where(touch, q[2] - low, q[2])
    vxy = v[:2]
    sp = jnp.sqrt(jnp.sum(vxy * vxy))
    keep = jnp.where(sp > 0.0, jnp.maximum(0.0, 1.0 - MU_GROUND * -v[2] / jnp.where(
        sp > 0.0, sp, 1.0)), 0.0)
    slid = jnp.concatenate([vxy * keep, jnp.zeros(4)])
    v = jnp.where(rest, slid, v)
    return RigidData(d.time, q.at[2].set(z), v, d.act, touch)


def up_z(d: RigidData):
    """R[2, 2]: the body z axis' world z component (below 0: upside down)."""
    q = d.qpos
    return 1.0 - 2.0 * (q[4] * q[4] + q[5] * q[5])
