"""The flight loop: one simulated clock, clocked components, MuJoCo physics.

Each control tick: read the state, step every component that is due (in the
order ``Run`` built them: sensors, tasks, navigation, stages, control, wind,
radio, energy, book, probes, telemetry, user components, end conditions),
then advance MuJoCo ``substeps`` physics steps in one C call and check for
contact crashes and unstable physics. No pandas, dicts or numpy allocation
per tick: the components keep preallocated buffers and Python floats.
"""

from __future__ import annotations

import math

import mujoco

from ..control.stages import DONE, STAGES, TAKEOFF
from ..errors import SimulationError

CRASH_SPEED = 2.0        # m/s: touching anything faster than this is a crash


def fly(run) -> None:
    """Fly ``run`` (an ``assemble.Run``) until a component ends it."""
    model, d, s = run.model, run.data, run.vehicle
    comps, nsub, step = run.components, run.plan.substeps, mujoco.mj_step
    qpos, qvel, sqrt = d.qpos, d.qvel, math.sqrt
    half_tick = 0.5 * nsub * model.opt.timestep      # a tick advances time by nsub steps
    ticking, clocked, ordered = schedule(comps)
    next_any = min([c.next_due for c in clocked], default=math.inf)
    while True:
        t = d.time
        s.q = q = qpos.tolist()
        s.v = v = qvel.tolist()
        z, vx, vy, vz = q[2], v[0], v[1], v[2]
        if not (z == z and abs(z) < 1e5 and vx == vx):
            raise SimulationError(
                f"simulation diverged at t = {t:.3f} s (position or velocity not finite: "
                f"z = {z!r}, vx = {vx!r}); check the blueprint's inertia and rotor "
                f"coefficients or lower the physics timestep")
        s.speed = sqrt(vx * vx + vy * vy + vz * vz)
        s.qc = q                     # the truth, unless a Navigation estimate replaces it
        s.vc = v
        if t >= next_any:
            for c, c_step in ordered:
                if t >= c.next_due:
                    c_step(t)
            next_any = min([c.next_due for c in clocked], default=math.inf)
        else:
            for c_step in ticking:
                c_step(t)
        if s.end_reason is not None:
            break
        step(model, d, nsub)
        if d.ncon > 0 and s.stage != DONE and _impact(d, s):
            s.crashed = True
            s.end_reason = "crashed"
            run.events.add(d.time, "crash", speed=s.speed)
            break
        if d.time < t + half_tick:                    # MuJoCo reset the state inside mj_step
            raise SimulationError(
                f"MuJoCo reset the simulation at t = {t:.3f} s (unstable physics: "
                f"{_warnings(d)}); check the blueprint or lower the physics timestep")
    t = d.time
    for c in comps:
        c.finish(t)


def schedule(comps) -> tuple[list, list, list]:
    """(ticking, clocked, ordered) of ``comps``: every-tick components run alone in the
    ticks where no clocked one is due (one comparison); otherwise every component is
    looked at, in order (``ordered``: (component, its step) pairs)."""
    ticking = [c.step for c in comps if c.every_tick]
    clocked = [c for c in comps if not c.every_tick]
    return ticking, clocked, [(c, c.step) for c in comps]


def _impact(d, s) -> bool:
    """Flipped over, or touched anything faster than CRASH_SPEED (not while
    still sitting on the pad at take-off)."""
    if d.xmat[1][8] < 0.0:
        return True
    if s.stage == TAKEOFF and s.q[2] < s.home[2] + 0.05:
        return False
    return s.speed > CRASH_SPEED


def _warnings(d) -> str:
    """The MuJoCo warnings raised so far (mjtWarning is not iterable in MuJoCo 4)."""
    names = sorted(n for n in dir(mujoco.mjtWarning) if n.startswith("mjWARN_"))
    hits = [n for n in names if d.warning[int(getattr(mujoco.mjtWarning, n))].number > 0]
    return ", ".join(hits) or "no MuJoCo warning recorded"


__all__ = ["CRASH_SPEED", "STAGES", "fly", "schedule"]
