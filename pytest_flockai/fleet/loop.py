"""The fleet's flight loop: one simulated clock, one MuJoCo model, N drones.

Each control tick: for every drone still flying, read its state from its
slice of the shared MjData and step its due components (the same order and
rule as ``mission.loop.fly``); then advance MuJoCo once for all drones and
check each drone's contacts. A drone touching another drone has crashed
(both have); a drone touching anything else faster than ``CRASH_SPEED`` or
flipped over has crashed. A drone whose flight ended (landed, crashed, battery,
time) is finished at that time and its motors stay off; the loop ends when
every drone has ended. A fleet's remote-inference offload (``offload.py``)
steps on the same clock, after the drones. The separation of every pair of airborne drones is
tracked at ``SEPARATION_HZ``.
"""

from __future__ import annotations

import math

import mujoco

from ..control.stages import DONE, TAKEOFF
from ..errors import SimulationError
from ..mission.loop import CRASH_SPEED, schedule

SEPARATION_HZ = 50.0


class _Member:
    """A drone of the loop: its run, state, data view and component lists."""

    __slots__ = ("run", "s", "view", "comps", "ticking", "clocked", "ordered", "next_any",
                 "qpos", "qvel", "active", "t_end")

    def __init__(self, run):
        self.run, self.s, self.view = run, run.vehicle, run.data
        self.comps = comps = run.components
        self.ticking, self.clocked, self.ordered = schedule(comps)
        self.next_any = min([c.next_due for c in self.clocked], default=math.inf)
        self.qpos, self.qvel = run.data.qpos, run.data.qvel
        self.active = True
        self.t_end = 0.0


def fly(model, data, runs, nsub: int, offload=None) -> dict:
    """Fly every run of the fleet; returns ``{"min_separation_m": m, "t_end": [s, ...]}``."""
    members = [_Member(r) for r in runs]
    live = list(members)                 # the drones still flying, in the fleet's order
    body_of = {r.data.body: i for i, r in enumerate(runs)}
    step, sqrt = mujoco.mj_step, math.sqrt
    half_tick = 0.5 * nsub * model.opt.timestep
    sep_period = 1.0 / SEPARATION_HZ
    t_sep = 0.0
    min_sep = math.inf
    while live:
        t = data.time
        ended = False
        for m in live:
            # the single flight's tick (mission.loop.fly), inline: this runs N x per tick
            s = m.s
            s.q = q = m.qpos.tolist()
            s.v = v = m.qvel.tolist()
            z, vx, vy, vz = q[2], v[0], v[1], v[2]
            if not (z == z and abs(z) < 1e5 and vx == vx):
                raise SimulationError(f"simulation diverged at t = {t:.3f} s for {s.name} "
                                      f"(position or velocity not finite: z = {z!r}, vx = {vx!r})")
            s.speed = sqrt(vx * vx + vy * vy + vz * vz)
            s.qc, s.vc = q, v
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
        if offload is not None and t >= offload.next_due:
            offload.step(t, members)
        if t >= t_sep:
            t_sep += sep_period
            if len(live) > 1:
                min_sep = min(min_sep, _separation(live, sqrt))
        step(model, data, nsub)
        if data.ncon > 0:
            _contacts(model, data, members, body_of)
            if not all(m.active for m in live):
                live = [m for m in live if m.active]
        if data.time < t + half_tick:                    # MuJoCo reset the state inside mj_step
            raise SimulationError(f"MuJoCo reset the fleet's simulation at t = {t:.3f} s "
                                  f"(unstable physics); check the blueprints or lower the "
                                  f"physics timestep")
    return {"min_separation_m": min_sep, "t_end": [m.t_end for m in members]}


def _end(m, t) -> None:
    """A drone's flight ended at ``t``: finish its components, motors off."""
    m.active = False
    m.t_end = t
    m.view.ctrl[:] = 0.0
    for c in m.comps:
        c.finish(t)


def _separation(live, sqrt) -> float:
    """The smallest distance between two drones in the air now (inf if < 2)."""
    pts = [m.s.q for m in live if m.s.airborne and m.s.stage != TAKEOFF]
    best = math.inf                    # squared: sqrt is monotonic, one sqrt at the end
    for i in range(len(pts) - 1):
        ax, ay, az = pts[i][:3]
        for b in pts[i + 1:]:
            dx, dy, dz = ax - b[0], ay - b[1], az - b[2]
            d = dx * dx + dy * dy + dz * dz
            if d < best:
                best = d
    return sqrt(best)


def _contacts(model, data, members, body_of) -> None:
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
        if what == "drone" or _impact(m):
            s.crashed = True
            s.end_reason = "crashed"
            m.run.events.add(data.time, "crash", speed=s.speed, against=what)
            _end(m, data.time)


def _impact(m) -> bool:
    """The single flight's rule (``mission.loop``): flipped over, or touched
    something faster than CRASH_SPEED (not while still on the pad at take-off)."""
    s = m.s
    if m.view.flipped():
        return True
    if s.stage == TAKEOFF and s.q[2] < s.home[2] + 0.05:
        return False
    return s.speed > CRASH_SPEED
