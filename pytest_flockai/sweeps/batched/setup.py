"""The host side of a batch: the variants' numbers stacked, the free bodies checked
against compiled models, the initial states built batched (numpy; the engine puts them
on the device)."""

from __future__ import annotations

import math
import pickle

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
from mujoco import mjx

from ...control.stages import TAKEOFF
from ...errors import FlockAIError
from ...mission.plan import resolve
from .. import axes as _axes
from . import params as P
from . import rigid as R

#: members of a batch whose derived free body is checked against a compiled model
CHECKED = 8


def checked(groups: dict) -> tuple[dict, int]:
    """The groups with every derived free body (``rigid_model.free_body``, key ending in
    ``("free", n)``) checked: ``CHECKED`` members of each group, evenly spread from the
    first to the last, are compiled and must hold the same numbers to 1e-12; where one
    differs, every member of that group is compiled (never a wrong number). Also the
    number of models compiled."""
    out: dict = {}
    compiled = 0
    for key, members in groups.items():
        if key[-1][0] != "free":
            compiled += len(members)
            out.setdefault(key, []).extend(members)
            continue
        picks = sorted(set(np.linspace(0, len(members) - 1, CHECKED).round().astype(int)))
        same = []
        for j in picks:
            body, new = compiled_body(members[j][1])
            compiled += new
            same.append(R.same_body(members[j][3], body))
        if all(same):
            out.setdefault(key, []).extend(members)
            continue
        for i, m, _, _ in members:                      # the derivation is off: compile all
            k, num, mdl = P.variant(m, None, "jax", derive=False)
            compiled += 1
            out.setdefault(k, []).append((i, m, num, mdl))
    return out, compiled


#: the compiled free bodies of the blueprints checked so far in this process, by what
#: MuJoCo's compile reads (the drone's blueprint, the physics step, the air density): a
#: later sweep of the same drones checks against them without compiling again
_COMPILED: dict = {}
_COMPILED_MAX = 4096


def compiled_body(m) -> tuple:
    """(the ``FreeBody`` of mission ``m``'s compiled MuJoCo model, 1 if compiled now, 0 if
    this process compiled the same blueprint before)."""
    plan = resolve(m)
    key = (repr(plan.drone.to_dict()), plan.physics_dt, plan.atmosphere.density)
    body = _COMPILED.get(key)
    if body is not None:
        return body, 0
    if len(_COMPILED) >= _COMPILED_MAX:
        _COMPILED.clear()
    body = _COMPILED[key] = P.compiled_body(m)
    return body, 1


#: variants built by earlier sweeps in this process, by (the base mission's pickle, the
#: physics, the variant's values): a repeated sweep builds none again
_BUILT: dict = {}
_BUILT_MAX = 8192


def built(base, physics: str):
    """``values -> (mission, key, numbers, model)`` of the variants of ``base`` (read-only
    copies: never flown), reusing what an earlier call built for a base mission with the
    same pickle (any change to the base, its drone or its pilot is a new pickle)."""
    try:
        base_key = (pickle.dumps(base, protocol=pickle.HIGHEST_PROTOCOL), physics)
    except (pickle.PicklingError, TypeError, AttributeError):   # not picklable: no reuse
        base_key = None

    def one(values):
        key = None if base_key is None else (base_key, repr(sorted(values.items())))
        out = _BUILT.get(key) if key is not None else None
        if out is None:
            m, fp = _axes.resolved(base, values, share=True)     # read only: never flown
            out = (m, *P.variant(m, fp, physics))
            if key is not None:
                if len(_BUILT) >= _BUILT_MAX:
                    _BUILT.clear()
                _BUILT[key] = out
        return out
    return one


def stack(items, to_jax: bool = True):
    """The variants' pytrees (``VariantParams``, states) stacked leaf by leaf into one
    pytree of batched arrays (numpy first: strongly typed, so the scan's output has the
    input's types and the chunk compiles once)."""
    treedef = jax.tree_util.tree_structure(items[0])
    cols = zip(*[jax.tree_util.tree_leaves(x) for x in items])
    out = [np.asarray(c) if np.ndim(c[0]) == 0 else np.stack(c) for c in cols]
    return jax.tree_util.tree_unflatten(treedef, [jnp.asarray(x) for x in out] if to_jax else out)


def to_jax(tree):
    """Numpy leaves as JAX arrays (the types the chunk's outputs have)."""
    return jax.tree_util.tree_map(jnp.asarray, tree)


def take(tree, sl):
    """The variants ``sl`` of a batched (numpy) pytree (a shard's)."""
    return jax.tree_util.tree_map(lambda x: x[sl], tree)


def models(models, dev):
    """(shared leaves, batched leaves by index, treedef) of the MJX models."""
    flat = [jax.tree_util.tree_flatten(mjx.put_model(m, device=dev)) for m in models]
    treedef = flat[0][1]
    if any(f[1] != treedef for f in flat[1:]):
        raise FlockAIError("sweep: backend='mjx': the variants' MuJoCo models differ in "
                           "structure; sweep the differing axis with backend='process'")
    leaves = flat[0][0]
    diff = {j: jnp.stack([f[0][j] for f in flat]) for j in range(len(leaves))
            if any(not np.array_equal(np.asarray(f[0][j]), np.asarray(leaves[j])) for f in flat[1:])}
    return leaves, diff, treedef


def data(members, dev, physics):
    """The physics' initial states, batched: MJX data after ``mj_forward``, or the free
    bodies at ``qpos0``."""
    if physics != "mjx":
        q0 = np.stack([mdl.qpos0 for *_, mdl in members])
        n, nu = q0.shape[0], len(members[0][3].rigid.tau)
        return R.RigidData(np.zeros(n), q0, np.zeros((n, 6)), np.zeros((n, nu)), np.zeros(n, bool))
    datas = []
    for *_, model in members:
        data = mujoco.MjData(model)
        mujoco.mj_forward(model, data)
        datas.append(mjx.put_data(model, data, device=dev))
    return stack(datas)


def init_states(p, d, w_g, nu: int) -> dict:
    """The variants' flight states, batched (numpy), from their stacked numbers ``p``
    (numpy), initial physics states ``d`` and wind filter states ``w_g`` (n, 3)."""
    n = len(w_g)
    z, f = np.zeros(n), (lambda *shape: np.zeros((n, *shape)))
    home = np.stack([z, z, np.asarray(d.qpos[:, 2], dtype=float)], axis=1)
    e_period = np.asarray(p.mission.energy_period, dtype=float)
    return {
        "d": d, "home": home, "stage": np.full(n, TAKEOFF, np.int32),
        "sp": np.concatenate([home, f(7)], axis=1), "t_stage": z, "leg_p0": home,
        "leg_p1": np.stack([z, z, np.asarray(p.pilot.altitude, dtype=float)], axis=1),
        "leg_speed": np.asarray(p.mission.climb_speed, dtype=float),
        "pilot_t0": z, "pilot_start": f(3), "t_land": np.full(n, math.nan), "integ": f(3),
        "airborne": np.ones(n, bool), "end": np.zeros(n, np.int32), "t_end_at": np.full(n, math.nan),
        "w_g": w_g, "w_coef": f(4), "w_h": np.full(n, math.nan),
        "w": np.asarray(p.wind.mean, dtype=float), "hb_next": z, "hb_pending": z, "hb_drained": z,
        "e_next": e_period, "t_e": z, "energy_j": z, "e_leaf": f(p.energy.const_w.shape[1]),
        "loss_j": z, "vi": np.asarray(p.motors.vi0, dtype=float), "vrel": f(3),
        "b_soc": np.ones(n), "b_below": z, "b_cut": np.zeros(n, bool), "b_v": z,
        "b_vmin": np.asarray(p.battery.v0, dtype=float), "b_next": z, "t_book": z, "acc": z,
        "pv": f(3), "ticks": np.zeros((n, 6), np.int32), "dist": z, "vmax": z, "terr": z,
        "ec_next": e_period, "speed": z, "landed": np.zeros(n, bool), "ctrl": f(nu)}
