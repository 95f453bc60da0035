"""The flight loop of 1..N drones: one simulated clock, one MuJoCo model,
clocked components per drone. A single Mission is a flight of one drone; a
fleet flies N in the same loop.

Each control tick: for every drone still flying, read its state from its slice
of the MjData (``t q v speed``) and step its components that are due, in the
order ``assemble.Run`` built them from the one table ``steps.STEP_ORDER``; a
drone whose flight ended (landed, battery, time, stopped) is finished at that
time and its motors stay off. Then the flight-wide steps that
are due (a fleet's offload and separation: ``step(t, drones)``), then MuJoCo
advances ``substeps`` physics steps in one C call, and the contacts are checked:
a drone touching another drone has crashed (both have); a drone flipped over, or
touching anything else faster than ``CRASH_SPEED`` (not while still on its pad at
take-off), has crashed. The loop ends when every drone has ended. With
``max_wall_s``, a watchdog (``watchdog.py``) interrupts a call that never returns
at the deadline: the flight stops as it does between ticks. No pandas,
dicts or numpy allocation per tick: the components keep preallocated buffers
and Python floats.
"""

from __future__ import annotations

import math

from .._mujoco import mujoco
from ..control.stages import DONE, STAGES, TAKEOFF
from ..errors import SimulationError
from .ending import WallClockGuard
from .watchdog import Overrun, watching

CRASH_SPEED = 2.0        # m/s: touching anything faster than this is a crash


class Member:
    """A drone of the loop: its run, state, data, body and component lists
    (``ticking``: every-tick components; ``ordered``: (component, step) pairs)."""

    __slots__ = ("run", "s", "data", "body", "comps", "ticking", "clocked", "ordered",
                 "next_any", "qpos", "qvel", "active", "t_end")

    def __init__(self, run):
        self.run, self.s, self.data, self.body = run, run.vehicle, run.data, run.body
        self.comps = comps = run.components
        self.ticking, self.clocked, self.ordered = schedule(comps)
        self.next_any = min([c.next_due for c in self.clocked], default=math.inf)
        self.qpos, self.qvel = run.data.qpos, run.data.qvel
        self.active = True
        self.t_end = 0.0


def fly(flight, steps=()) -> list:
    """Fly every drone of ``flight`` (an ``assemble.Flight``) until each has ended;
    ``steps``: flight-wide steps (``next_due``, ``step(t, drones)``) after the drones'
    components. Sets each run's ``t_end``; returns the loop's drones (``Member``).
    With ``max_wall_s``, a call that never returns is interrupted at the deadline
    (``watchdog.py``): the same ``SimulationError`` as between ticks, naming the call."""
    members = [Member(r) for r in flight.runs]
    guards = [c for m in members for c in m.comps if isinstance(c, WallClockGuard)]
    deadline = min([g.deadline for g in guards], default=None)
    try:
        with watching(deadline):
            return _fly(flight, members, steps)
    except Overrun as exc:
        err = SimulationError(
            f"Mission: max_wall_s = {min(g.max_wall_s for g in guards):g} s of host time "
            f"exceeded at t = {flight.data.time:.3f} s simulated inside a call that did not "
            f"return ({getattr(exc, 'where', Overrun.where)}); the call was interrupted and "
            f"the flight stopped (the partial result is on this error's .result)")
        err.end_reason = "wall_time"
        raise err from None


def _fly(flight, members, steps) -> list:
    model, data, runs = flight.model, flight.data, flight.runs
    nsub = runs[0].plan.substeps
    live = list(members)                 # the drones still flying, in the given order
    body_of = {m.body: i for i, m in enumerate(members)}
    step, sqrt = mujoco.mj_step, math.sqrt
    half_tick = 0.5 * nsub * model.opt.timestep      # a tick advances time by nsub steps
    next_step = min([st.next_due for st in steps], default=math.inf)
    while live:
        t = data.time
        ended = False
        for m in live:
            s = m.s
            s.q = q = m.qpos.tolist()
            s.v = v = m.qvel.tolist()
            z, vx, vy, vz = q[2], v[0], v[1], v[2]
            if not (z == z and abs(z) < 1e5 and vx == vx):
                raise SimulationError(
                    f"simulation diverged at t = {t:.3f} s for {s.name} (position or velocity "
                    f"not finite: z = {z!r}, vx = {vx!r}); check the blueprint's inertia and "
                    f"rotor coefficients or lower the physics timestep")
            s.speed = sqrt(vx * vx + vy * vy + vz * vz)
            s.qc = q                     # the truth, unless a Navigation estimate replaces it
            s.vc = v
            if t >= m.next_any:
                for c, c_step in m.ordered:
                    if t >= c.next_due:
                        c_step(t)
                m.next_any = min([c.next_due for c in m.clocked], default=math.inf)
            else:
                for c_step in m.ticking:
                    c_step(t)
            if s.end_reason is not None:
                _end(m, t)
                ended = True
        if ended:
            live = [m for m in live if m.active]
            if not live:
                break
        if t >= next_step:
            for st in steps:
                if t >= st.next_due:
                    st.step(t, members)
            next_step = min([st.next_due for st in steps])
        step(model, data, nsub)
        if data.ncon > 0:
            _contacts(model, data, members, body_of)
            if not all(m.active for m in live):
                live = [m for m in live if m.active]
        if data.time < t + half_tick:                    # MuJoCo reset the state inside mj_step
            raise SimulationError(
                f"MuJoCo reset the simulation at t = {t:.3f} s (unstable physics: "
                f"{_warnings(data)}); check the blueprint or lower the physics timestep")
    return members


def schedule(comps) -> tuple[list, list, list]:
    """(ticking, clocked, ordered) of ``comps``: every-tick components run alone in the
    ticks where no clocked one is due (one comparison); otherwise every component is
    looked at, in order (``ordered``: (component, its step) pairs)."""
    ticking = [c.step for c in comps if c.every_tick]
    clocked = [c for c in comps if not c.every_tick]
    return ticking, clocked, [(c, c.step) for c in comps]


def _end(m, t) -> None:
    """A drone's flight ended at ``t``: motors off, finish its components."""
    m.active = False
    m.t_end = m.run.t_end = t
    m.data.ctrl[:] = 0.0
    for c in m.comps:
        c.finish(t)


def _contacts(model, data, members, body_of) -> None:
    """Crashes from this step's contacts (see the module docstring)."""
    bodies = model.geom_bodyid[data.contact.geom[:data.ncon]].tolist()
    hit = set()
    for b1, b2 in bodies:
        i1, i2 = body_of.get(b1), body_of.get(b2)
        if i1 is not None and i2 is not None:           # drone on drone: both crash
            for i in (i1, i2):
                hit.add((i, "drone"))
        else:
            for i in (i1, i2):
                if i is not None:
                    hit.add((i, "other"))
    for i, what in sorted(hit):
        m = members[i]
        s = m.s
        if not m.active or s.stage == DONE or s.end_reason is not None:
            continue
        if what == "drone" or _impact(data, m):
            s.crashed = True
            s.end_reason = "crashed"
            m.run.events.add(data.time, "crash", speed=s.speed, against=what)
            _end(m, data.time)


def _impact(data, m) -> bool:
    """Flipped over (the body's z axis points below the horizon), or touched
    anything faster than CRASH_SPEED (not while still sitting on the pad at take-off)."""
    s = m.s
    if data.xmat[m.body][8] < 0.0:
        return True
    if s.stage == TAKEOFF and s.q[2] < s.home[2] + 0.05:
        return False
    return s.speed > CRASH_SPEED


def _warnings(d) -> str:
    """The MuJoCo warnings raised so far (mjtWarning is not iterable in MuJoCo 4)."""
    names = sorted(n for n in dir(mujoco.mjtWarning) if n.startswith("mjWARN_"))
    hits = [n for n in names if d.warning[int(getattr(mujoco.mjtWarning, n))].number > 0]
    return ", ".join(hits) or "no MuJoCo warning recorded"


__all__ = ["CRASH_SPEED", "STAGES", "Member", "fly", "schedule"]
