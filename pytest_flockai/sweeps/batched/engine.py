"""Fly a sweep's variants in batches: the core's components in JAX, on MJX's physics
or the free-flying rigid body (``rigid.py``).

Variants with the same structure (``params.variant``'s key: rates, rotor count,
energy leaves, pilot) fly in one batch, padded to a bucket size (``bucket``). With
``physics="mjx"`` their MuJoCo models go to MJX (``mjx.put_model``) and the fields
that differ (mass, inertia, thrust limits) are stacked; with ``"jax"`` each
variant's ``RigidModel`` is. One control tick is the core's loop
(``mission/loop.py``) in the core's order: stage machine, controller, wind,
heartbeats, energy integrator, flight book, end conditions, then ``substeps``
physics steps with the body and rotor drag applied at the centre of mass, and the
crash check. ``jax.lax.scan`` runs ``CHUNK_S`` of simulated time per call; the host
loops over chunks until every variant has ended, feeding each variant's own wind
noise (the core's random stream: same seed, same gusts). A variant that has ended
keeps its state. Float64 throughout (``jax.enable_x64`` around the backend): the
time sum and the energy integral of a 30-minute flight drift visibly in float32.
"""
from __future__ import annotations

import functools
import gc
import math
import time
from types import SimpleNamespace
from typing import cast

import jax
import jax.numpy as jnp
import numpy as np
from mujoco import mjx

from ...control.stages import DONE, TAKEOFF
from ...errors import FlockAIError
from . import compile_cache, cpu_threads, setup, shards
from . import control as C
from . import energy as E
from . import params as P
from . import rigid as R
from . import rows as _rows

#: s of simulated time per compiled chunk (the host checks for the end between chunks)
CHUNK_S = 2.0
_END = {name: i for i, name in enumerate(P.END_REASONS)}
#: wall (and CPU) seconds of the last ``fly`` in this process: the variants' numbers and
#: models (``variants_s``) and the batches (``batch_s``: states, compile or load, chunks);
#: ``compiled``: MuJoCo models compiled (the free body derives the others, ``setup.checked``)
LAST_TIMINGS: dict = {}


def fly(base, plan: list[dict], device: str | None = None, physics: str = "mjx") -> list[dict]:
    """One row dict per variant, in the plan's order (as ``runner._fly``); ``physics``:
    "mjx" (MJX's ``mjx.step``) or "jax" (``rigid.step``, the free-flight body)."""
    shards.wanted()                         # a bad $FLOCKAI_JAX_CPU_SHARDS: before anything
    threads = cpu_threads.start(device)     # first: before anything starts JAX's client
    n_shards = shards.count(device)
    t0, c0 = time.perf_counter(), time.process_time()
    rows: list[dict | None] = [None] * len(plan)
    groups: dict = {}
    collect = gc.isenabled()
    gc.disable()            # thousands of objects kept for the batch: no collector passes over
    # them while they are built (garbage is collected after)
    try:
        _variants(base, plan, physics, rows, groups)
    finally:
        if collect:
            gc.enable()
    groups, compiled = setup.checked(groups)
    devs = (jax.devices("cpu")[:n_shards] if n_shards > 1
            else [jax.devices(device)[0] if device else jax.devices()[0]])
    compile_cache.enable()
    LAST_TIMINGS.update(variants_s=time.perf_counter() - t0, batch_s=0.0,
                        variants_cpu_s=time.process_time() - c0, batch_cpu_s=0.0,
                        compiled=compiled, jax_cpu_threads=threads, jax_cpu_shards=1)
    with jax.enable_x64(True):
        for key, members in groups.items():
            t1, c1 = time.perf_counter(), time.process_time()
            k = max(1, min(n_shards, len(members)))
            LAST_TIMINGS["jax_cpu_shards"] = max(LAST_TIMINGS["jax_cpu_shards"], k)
            out = _fly_group(key, members, devs[:k], physics)
            LAST_TIMINGS["batch_s"] += time.perf_counter() - t1
            LAST_TIMINGS["batch_cpu_s"] += time.process_time() - c1
            for (i, _, _, _), row in zip(members, out):
                rows[i] = {**plan[i], **row}
    return cast(list[dict], rows)       # every variant has its row (flown, or its error)


def bucket(n: int) -> int:
    """The batch size ``n`` variants fly in: the next of 8, 16, 32, ... 1,024 and then
    multiples of 1,024 (1,000 and 1,024 variants share one compiled chunk; the padding
    repeats the last variant and its rows are dropped)."""
    if n >= 1024:
        return -(-n // 1024) * 1024
    return max(8, 1 << (n - 1).bit_length())


def _fly_group(key, members, devs, physics) -> list[dict]:
    """One group's rows: its variants split in order over the devices ``devs`` (the
    shards, ``shards.py``: one bucket each, padded at the end by repeating the last
    variant), each shard's chunks dispatched before any is waited for, so the shards run
    at once, one XLA thread each."""
    nsub, _, ctrl_dt, book_dt, _, (kinds, tops), pkind = key[:7]
    real = len(members)
    size = bucket(-(-real // len(devs)))
    members = members + [members[-1]] * (-(-real // size) * size - real)
    nums = [num for _, _, num, _ in members]
    if physics == "mjx":
        leaves, diff, treedef = setup.models([mdl for *_, mdl in members], devs[0])
        idx, dvals = tuple(sorted(diff)), tuple(np.asarray(diff[j]) for j in sorted(diff))
        nu = members[0][3].nu
    else:
        leaves, idx, treedef = (), None, None
        dvals = setup.stack([mdl.rigid for *_, mdl in members], to_jax=False)
        nu = len(members[0][3].rigid.tau)
    samplers = []
    w_g = np.zeros((len(members), 3))
    for b, (_, m, _, _) in enumerate(members):
        smp = None
        if m.wind is not None and m.wind.turbulent:
            smp = m.wind.sampler(P.wind_rng(m), ctrl_dt)
            w_g[b] = np.asarray(smp.g, dtype=float)
        samplers.append(smp)
    cpu = devs[0].platform == "cpu"
    step = _chunk_fn(idx, treedef, nsub, ctrl_dt, book_dt, book_dt == ctrl_dt, kinds, pkind, cpu)
    parts = []
    for j in range(len(members) // size):
        sl, dev = slice(j * size, (j + 1) * size), devs[j]
        put = functools.partial(jax.device_put, device=dev)  # committed, like the chunk's
        # outputs: uncommitted inputs would compile the chunk a second time
        p_np = setup.stack(nums[sl], to_jax=False)
        s = setup.init_states(p_np, setup.data(members[sl], dev, physics), w_g[sl], nu)
        parts.append(SimpleNamespace(sl=sl, dev=dev, shared=put(tuple(leaves)), p=put(
            setup.to_jax(p_np)), dv=put(setup.to_jax(setup.take(dvals, sl))),
            s=put(setup.to_jax(s)), ended=False))
    chunk_ticks = max(1, int(round(CHUNK_S / ctrl_dt)))
    t_end = max(num.mission.t_end for num in nums)
    t = 0.0
    while True:
        noise = np.zeros((chunk_ticks, len(members), 3))
        for b, smp in enumerate(samplers):
            if smp is not None:
                noise[:, b, :] = smp.rng.standard_normal(3 * chunk_ticks).reshape(chunk_ticks, 3)
        live = [part for part in parts if not part.ended]   # a shard whose variants all
        for part in live:                   # ended keeps its state; dispatched: run at once
            part.s = step(part.shared, part.dv, part.p, part.s,
                          jax.device_put(noise[:, part.sl], part.dev))
        t += chunk_ticks * ctrl_dt
        for part in live:
            part.ended = bool(jnp.all(part.s["end"] != 0))
        if all(part.ended for part in parts) or t > t_end + 2 * CHUNK_S:
            break
    out = [_finish_fn(kinds, cpu)(part.p, part.s) for part in parts]
    host = jax.device_get(out)
    s = jax.tree_util.tree_map(lambda *xs: np.concatenate(xs), *host) if len(host) > 1 else host[0]
    return _rows.rows(s, nums[:real], tops, book_dt)


@functools.lru_cache(maxsize=16)
def _chunk_fn(diff_idx, treedef, nsub, ctrl_dt, book_dt, book_every, kinds, pkind, cpu=True):
    """The compiled chunk of one batch structure (cached: a second sweep of the same
    structure does not compile again). One tick is vmapped in parts; the clocked parts
    (energy, and the book when it is slower than the tick) run under a ``lax.cond`` on
    the whole batch, so the ticks where no variant's clock is due skip them (every
    variant starts at t = 0 on the same clock)."""
    def model(shared, dvals):
        if treedef is None:                   # the free-flight body: its model is dvals
            return dvals
        ls = list(shared)
        for j, val in zip(diff_idx, dvals):
            ls[j] = val
        return jax.tree_util.tree_unflatten(treedef, ls)

    def clocked(fn, due, p, s):
        """``fn`` on the batch where any variant is due (``fn`` selects per variant)."""
        return jax.lax.cond(jnp.any(jax.vmap(due)(s)),
                            lambda st: _like(st, jax.vmap(fn)(p, st)), lambda st: st, s)

    def tick(shared, dvals, p, s, noise):
        old = s
        s, landed = _stages(p, s, pkind)
        yaw = s["sp"][:, 9]                   # cos/sin of the yaw setpoints (1, 0 for 0)
        cs = jax.lax.cond(jnp.all(yaw == 0.0), lambda: (jnp.ones_like(yaw), jnp.zeros_like(yaw)),
                          lambda: (jnp.cos(yaw), jnp.sin(yaw)))
        s, w = jax.vmap(lambda p1, s1, l1, c1: _pre(p1, s1, l1, c1, ctrl_dt))(p, s, landed, cs)
        s = _like(old, {**s, "ctrl": _mix(p, w, s["stage"] == DONE)})
        s = jax.lax.cond(jnp.any(p.wind.active), lambda st: _like(st, jax.vmap(
            lambda p1, s1, n1: _wind(p1, s1, n1, ctrl_dt))(p, st, noise)), lambda st: st, s)
        s = clocked(lambda p1, s1: _energy(p1, s1, kinds), lambda s1: E.due(s1["d"].time, s1["e_next"]),
                    p, s)
        book = lambda p1, s1: _book(p1, s1, book_dt, book_every)  # noqa: E731
        s = _like(old, jax.vmap(book)(p, s)) if book_every else clocked(
            book, lambda s1: E.due(s1["d"].time, s1["b_next"]), p, s)
        post = jax.vmap(lambda dv, p1, s1: _post(model(shared, dv), p1, s1, ctrl_dt, nsub),
                        in_axes=(0, 0, 0))
        s = _like(old, post(dvals, p, s))
        return jax.lax.cond(jnp.any(old["end"] != 0), lambda: jax.vmap(  # an ended variant
            lambda a, b: _sel(a["end"] != 0, a, b))(old, s), lambda: s)  # keeps its state

    def run(shared, dvals, p, s, noise):
        # the chunk's ticks until every variant of the shard has ended: an ended variant
        # keeps its state, so the ticks left out would change no row (a flight that ends
        # early in a chunk no longer pays for the rest of it)
        def more(c):
            return (c[0] < noise.shape[0]) & jnp.any(c[1]["end"] == 0)

        def one(c):
            return c[0] + 1, tick(shared, dvals, p, c[1], noise[c[0]])
        return jax.lax.while_loop(more, one, (jnp.zeros((), jnp.int32), s))[1]
    return jax.jit(run, compiler_options=compile_cache.options(cpu))


@functools.lru_cache(maxsize=16)
def _finish_fn(kinds, cpu=True):
    """``_finish`` on the batch, compiled (op by op it costs ~0.1 s of dispatch)."""
    return jax.jit(jax.vmap(lambda p1, s1: _finish(p1, s1, kinds)),
                   compiler_options=compile_cache.options(cpu))


def _variants(base, plan, physics, rows, groups) -> None:
    """Each variant's (key, numbers, model) into ``groups`` by key, or its error row
    (reused from an earlier call on the same base mission: ``setup.built``)."""
    built = setup.built(base, physics)
    for i, values in enumerate(plan):
        try:
            m, key, num, model = built(values)
        except FlockAIError as exc:
            rows[i] = {**values, "end_reason": "error", "error": f"{type(exc).__name__}: {exc}",
                       "sim_time_s": math.nan}
            continue
        groups.setdefault(key, []).append((i, m, num, model))


def _like(ref, new):
    """``new`` with the dtypes of ``ref`` (the scan's carry and both branches of a cond)."""
    return jax.tree_util.tree_map(lambda a, b: jnp.asarray(b, dtype=a.dtype), ref, new)


def _contact(d):
    if isinstance(d, R.RigidData):
        return d.contact
    c = d._impl.contact
    return jnp.any(c.dist < c.includemargin) if c.dist.shape[0] else jnp.zeros((), bool)


def _mix(p, w, off):
    """The rotor thrusts of the controllers' wrenches ``w`` (``C.mix``): the saturated
    mixer only when some variant's allocation leaves a rotor's range (batch-level
    ``lax.cond``); 0 where the flight is done."""
    f = jax.vmap(lambda p1, w1: C.allocate(p1.ctrl.B, *w1))(p, w)
    ok = jax.vmap(C.fits)(f, p.ctrl.fmax)
    f = jax.lax.cond(jnp.all(ok), lambda: f, lambda: jnp.where(ok[:, None], f, jax.vmap(
        lambda p1, w1: C.saturated(p1.ctrl.B, p1.ctrl.fmax, *w1))(p, w)))
    return jnp.where(off[:, None], 0.0, f)


def _when(flag, fn, *args):
    """``fn(*args)`` if ``flag`` (a batch-level ``lax.cond``), else zeros of its shape (read
    by no variant: the caller's ``flag`` says where the result applies)."""
    shape = jax.eval_shape(fn, *args)
    return jax.lax.cond(flag, lambda: fn(*args), lambda: jax.tree_util.tree_map(
        lambda x: jnp.zeros(x.shape, x.dtype), shape))


def _stages(p, s, pkind):
    """``C.stages`` on the batch: the leg's setpoint, the take-off's end and what follows
    the pilot only on ticks where some variant is in a leg stage / ends its take-off /
    ends its pilot (the same parts, so the same numbers): (state, landed)."""
    V = jax.vmap
    d, stage = s["d"], s["stage"]
    pil = V(lambda p1, s1: C.pilot_update(p1, s1, s1["d"].time, pkind))(p, s)
    is_leg = (stage != C.PILOT) & (stage != DONE)
    lg = _when(jnp.any(is_leg), V(lambda p1, s1: C.leg_setpoint(p1, s1, s1["d"].time)), p, s)
    to_pilot = is_leg & (d.time - s["t_stage"] >= lg[3]) & (stage == TAKEOFF)
    take = _when(jnp.any(to_pilot), V(
        lambda p1, s1: C.takeoff_done(p1, s1, s1["d"].time, s1["d"].qpos, pkind)), p, s)
    aft = _when(jnp.any((stage == C.PILOT) & pil[1]), V(
        lambda p1, s1, h: C.after_pilot(p1, s1, h, False)), p, s, pil[0][:, :3])
    return V(lambda p1, s1, pl, lg1, tk, af: C.combine(
        p1, s1, s1["d"].time, s1["d"].qvel, _contact(s1["d"]), pl, lg1, tk, af))(
        p, s, pil, lg, take, aft)


def _pre(p, s, landed, yaw_cs, ctrl_dt):
    """The tick after the stage machine (``_stages``) up to the wind: controller (up to the
    mixer: ``_mix``), heartbeats: (state, wrench)."""
    d = s["d"]
    t, q, v = d.time, d.qpos, d.qvel
    speed = jnp.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])   # the core's order, on any shard
    w, integ = C.wrench(p.ctrl, s["integ"], q, v, s["sp"], ctrl_dt, yaw_cs)
    off = s["stage"] == DONE
    s = {**s, "speed": speed, "integ": jnp.where(off, s["integ"], integ),
         "airborne": s["airborne"] & ~off, "landed": landed}
    hb = E.due(t, s["hb_next"])
    return {**s, "hb_next": s["hb_next"] + jnp.where(hb, p.mission.hb_period, 0.0),
            "hb_pending": s["hb_pending"] + jnp.where(hb, 1.0, 0.0)}, w


def _wind(p, s, noise, ctrl_dt):
    """``WindStep.step`` (skipped on a batch without turbulence: its air is the mean)."""
    w, wst = E.wind_step(p.wind, s, s["d"].qpos[2], noise, ctrl_dt)
    return {**s, **wst, "w": w}


def _energy(p, s, kinds):
    """``EnergyIntegrator.step`` where due: the interval charged at the tick's rotor state."""
    d = s["d"]
    t = d.time
    vrel = C.rotation(d.qpos[3:7]).T @ (d.qvel[:3] - s["w"])
    es = E.integrate(p, {**s, "vrel": vrel}, t, d.act, vrel, s["airborne"], kinds)
    es["e_next"] = s["e_next"] + p.mission.energy_period
    return _sel_keys(E.due(t, s["e_next"]), es, s)


def _book(p, s, book_dt, book_every):
    """``FlightBook.step`` where due."""
    d = s["d"]
    t = d.time
    bs = E.book(p, s, t, d.qpos, d.qvel, s["speed"], book_dt, book_every)
    return {**s, **bs} if book_every else _sel_keys(E.due(t, s["b_next"]), {**s, **bs}, s)


def _post(m, p, s, ctrl_dt, nsub):
    """End conditions, the divergence check, then the physics over the tick."""
    d = s["d"]
    t, q, v = d.time, d.qpos, d.qvel
    ok = jnp.isfinite(q[2]) & (jnp.abs(q[2]) < 1e5) & jnp.isfinite(v[0])
    s = _end_conditions(p, s, t, ctrl_dt, s["landed"])
    s = {**s, "end": jnp.where(ok, s["end"], _END["diverged"])}
    stepped = _physics(m, p, s, d, s["ctrl"], nsub)
    return _sel_keys(s["end"] != 0, s, stepped, ("d", "end", "t_end_at"))


def _end_conditions(p, s, t, dt, landed):
    """``EndConditions.step`` where due (its clock, and every tick near the end)."""
    on_clock = E.due(t, s["ec_next"])
    run = on_clock | (t >= p.mission.t_end - dt - E.CLOCK_EPS)
    end = jnp.where(landed, _END["landed"], s["end"])
    live = run & (end == 0)
    empty = live & ((s["energy_j"] >= p.mission.e_usable) | s["b_cut"])
    end = jnp.where(empty, _END["battery_depleted"], end)
    reserve = live & ~empty & p.mission.use_reserve & (s["stage"] == C.PILOT) & (
        p.mission.e_usable - s["energy_j"] <= p.mission.reserve_j)
    s = C.go_home(p, s, t, reserve)
    timeout = live & ~empty & (t + 0.5 * dt >= p.mission.t_end)
    end = jnp.where(timeout, jnp.where(p.mission.timed, _END["time"], _END["time_cap"]), end)
    return {**s, "end": end, "ec_next": s["ec_next"] + jnp.where(on_clock, p.mission.energy_period, 0.0)}


def _physics(m, p, s, d, ctrl, nsub):
    """``substeps`` MJX steps with the body drag (every step, as MuJoCo's fluid model) and
    the rotor drag (from the tick's state, held over the tick as ``RotorDrag``), then the
    crash check (``loop._impact``)."""
    hf, hm = E.rotor_drag(p.aero, d.qpos[3:7], d.qvel, s["w"], d.act)
    if isinstance(d, R.RigidData):
        def free(_, dd):
            f = E.drag(p.aero, dd.qpos[3:7], dd.qvel[:3], s["w"])
            return R.step(m, dd, ctrl, jnp.concatenate([f + hf, hm]))
        touched = jnp.zeros((), bool)
        for k in range(nsub):                 # unrolled: XLA fuses across the substeps
            d = free(k, d)
            touched = touched | d.contact
        # a touch in any substep counts (MuJoCo's soft contact lasts a few ms, the hard
        # floor's only the substep that stops the fall: the next one may lift off it)
        return _crash(s, d._replace(contact=touched), R.up_z(d) < 0.0)
    d = d.replace(ctrl=ctrl)

    def sub(_, dd):
        f = E.drag(p.aero, dd.qpos[3:7], dd.qvel[:3], s["w"])
        xf = jnp.zeros_like(dd.xfrc_applied).at[1, :3].set(f + hf).at[1, 3:].set(hm)
        out = mjx.step(m, dd.replace(xfrc_applied=xf))
        return jax.tree_util.tree_map(lambda a, b: b.astype(a.dtype), dd, out)
    d = jax.lax.fori_loop(0, nsub, sub, d)
    return _crash(s, d, d.xmat[1, 2, 2] < 0.0)


def _crash(s, d, flipped):
    """``loop._impact``: touching the ground upside down, or fast away from the pad."""
    on_pad = (s["stage"] == TAKEOFF) & (s["d"].qpos[2] < s["home"][2] + 0.05)
    crash = _contact(d) & (s["stage"] != DONE) & (flipped | (~on_pad & (s["speed"] > 2.0)))
    return {**s, "d": d, "end": jnp.where(crash, _END["crashed"], s["end"]),
            "t_end_at": jnp.where(crash, d.time, s["t_end_at"])}


def _finish(p, s, kinds):
    """``EnergyIntegrator.finish``: the last, partial interval (the last usage's
    air-relative velocity, as the core)."""
    t = s["d"].time
    es = E.integrate(p, s, t, s["d"].act, s["vrel"], s["airborne"], kinds)
    return _sel(t > s["t_e"], es, s)


def _sel_keys(cond, a: dict, b: dict, keys=None) -> dict:
    """``_sel`` on the entries that may differ (``keys``, else those not the same object):
    the rest of the state is passed through, not selected leaf by leaf."""
    keys = [k for k in a if a[k] is not b[k]] if keys is None else keys
    return {**b, **_sel(cond, {k: a[k] for k in keys}, {k: b[k] for k in keys})}


def _sel(cond, a: dict, b: dict) -> dict:
    """``a`` where ``cond``, else ``b`` (dicts of arrays and MJX data, same keys)."""
    return jax.tree_util.tree_map(lambda x, y: jnp.where(cond, x, y), a, b)
