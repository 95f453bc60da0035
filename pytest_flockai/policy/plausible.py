"""The searches' plausibility gate: a target is judged before a search acts on it.

``SearchThenOrbit`` and ``SharedSearch`` act on a track at its confirmation (``confirm`` hits, 2
by default), before the tracker's speed gate (``follow.SPEED_HITS`` = 3 hits) can judge it. So at
confirmation a search compares the track's raw hits, first to last: ``d_t`` the ground
displacement of the measured points, ``d_d`` the drone's own displacement (its navigation
estimate at the same captures), ``dt`` the time between them. The target is implausible when

- it moves faster than its class can (``|d_t| / dt`` above ``follow.MAX_SPEED_MPS``: a person
  10.4 m/s, the 100 m world record; a vehicle 250 km/h), or
- it moves with the drone: the drone moved at least ``BASELINE_M`` and the target's
  displacement differs from the drone's by at most ``WITH_DRONE`` (0.5) of it. A box stuck at
  one pixel maps to a ground point at a fixed offset from the drone: ``d_t = d_d`` up to the
  attitude's sway. A person standing still gives ``|d_t - d_d| = |d_d|``; one walking at
  1.4 m/s under a drone flying its plan at 6 m/s, at least 4.6/6 of it.

Limits: with less than ``BASELINE_M`` of drone motion between the hits (hovering, a slow
orbit) nothing is judged by the second rule (a box stuck in the image of a still drone is a
still point on the ground, like a person standing); a real target moving with the drone at
more than half its speed in the same direction is rejected too.

A rejected target resets the tracker and is remembered as a phantom: its offset from the drone
in the drone's own frame (forward, left). Later points within ``PHANTOM_M`` of a phantom's
offset are not fused, so a box stuck in the image does not hold the tracker from the people
around it (the last ``PHANTOMS`` phantoms are kept)."""

from __future__ import annotations

import math

#: m: the least drone motion between a track's first and last hit for the "moves with the
#: drone" rule to judge: 2.5 times the tracker's 1 m measurement noise (``control.tracking``)
BASELINE_M = 2.5
#: m/s: the fastest a person walks: the highest mean maximum gait speed in Bohannon 1997
#: (Age and Ageing 26(1), Table: men in their 40s, 253 cm/s; comfortable paces 127-146 cm/s)
WALK_MAX_MPS = 2.53
#: s: a track seen while the drone moved less than ``BASELINE_M`` waits this long for more
#: hits before it is acted on unjudged (a hovering drone)
WAIT_S = 5.0
#: the target moves with the drone when |d_t - d_d| <= WITH_DRONE * |d_d|
WITH_DRONE = 0.5
#: m: points this close (in the drone's frame) to a phantom's offset are not fused
PHANTOM_M = 3.0
#: phantoms remembered per policy
PHANTOMS = 4


def offset(p, nav) -> tuple[float, float]:
    """(forward, left) metres of ground point ``p`` from the drone at ``nav`` = (x, y, yaw)."""
    dx, dy = p[0] - nav[0], p[1] - nav[1]
    c, s = math.cos(nav[2]), math.sin(nav[2])
    return c * dx + s * dy, -s * dx + c * dy


def masked(p, nav, phantoms) -> bool:
    """True when ``p`` seen from ``nav`` lies where a phantom stays in the drone's frame."""
    o = offset(p, nav)
    return any(math.dist(o, f) <= PHANTOM_M for f in phantoms)


def judge(hits, max_speed: float):
    """None when the track whose raw ``hits`` [(t, (px, py), (nx, ny, yaw)), ...] are given
    is plausible (or cannot be judged, after ``WAIT_S``), ``("wait", {})`` while it cannot be
    judged yet, else ``(reason, info)`` (the module docstring's rules). The window judged ends
    at the last hit and starts at the latest hit the drone has moved far and fast enough
    from."""
    if len(hits) < 2:
        return None
    t1, p1, n1 = hits[-1]
    for i in range(len(hits) - 2, -1, -1):
        t0, p0, n0 = hits[i]
        ddx, ddy = n1[0] - n0[0], n1[1] - n0[1]
        drone = math.hypot(ddx, ddy)
        if drone >= max(BASELINE_M, 2.0 * WALK_MAX_MPS * (t1 - t0)):
            break
    else:                       # a still drone cannot judge: act after WAIT_S
        n0 = hits[0][2]
        still = math.hypot(n1[0] - n0[0], n1[1] - n0[1]) < BASELINE_M
        return None if still and t1 - hits[0][0] >= WAIT_S else ("wait", {})
    dtx, dty = p1[0] - p0[0], p1[1] - p0[1]
    dt = t1 - t0
    if dt > 0.0 and math.hypot(dtx, dty) / dt > max_speed:
        return "faster", {"speed_mps": round(math.hypot(dtx, dty) / dt, 2),
                          "max_speed_mps": round(max_speed, 2)}
    rel = math.hypot(dtx - ddx, dty - ddy)
    if rel <= WITH_DRONE * drone:
        return "with_drone", {"target_moved_m": round(math.hypot(dtx, dty), 2),
                              "drone_moved_m": round(drone, 2), "relative_m": round(rel, 2)}
    return None


__all__ = ["BASELINE_M", "PHANTOM_M", "PHANTOMS", "WAIT_S", "WALK_MAX_MPS", "WITH_DRONE", "judge", "masked", "offset"]
