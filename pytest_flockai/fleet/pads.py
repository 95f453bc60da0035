"""Pads against the world: a drone standing inside a building, or so close to a wall
that its rotors touch it, cannot take off; ``Fleet`` refuses such a pad by name,
and ``survey(..., world=...)`` moves its default pads to the nearest free ground.

The obstacles are the world's buildings (``World.urban``/``World.scene``) and the
axis-aligned boxes of an MJCF world that stand on the ground.
"""

from __future__ import annotations

import math

import numpy as np

#: m: the least distance from a pad to a wall. A pad is a drone's centre: the largest
#: built-in airframe, the DJI Matrice 300 RTK, has a 0.895 m diagonal wheelbase and
#: 21 in (0.533 m) propellers (DJI spec sheet): 0.71 m from its centre to a blade tip,
#: so 1 m keeps every built-in drone's rotors clear of the wall
PAD_WALL_CLEARANCE_M = 1.0
#: m: a box whose bottom is below this stands on the ground (an obstacle for a pad)
_ON_GROUND_M = 0.5
#: m: how far ``free_pad`` looks for free ground, and its grid step
SEARCH_RADIUS_M, SEARCH_STEP_M = 100.0, 0.5


def obstacles(world) -> np.ndarray:
    """(N, 5) rows (x0, y0, x1, y1, top): footprints on the ground and their heights."""
    if world is None:
        return np.zeros((0, 5))
    rows = []
    b = np.asarray(getattr(world, "buildings", np.zeros((0, 5))), dtype=float).reshape(-1, 5)
    for cx, cy, hx, hy, h in b:
        rows.append((cx - hx, cy - hy, cx + hx, cy + hy, h))
    occ = np.asarray(getattr(world, "occluders", np.zeros((0, 6))), dtype=float).reshape(-1, 6)
    for x0, y0, z0, x1, y1, z1 in occ:
        if z0 < _ON_GROUND_M and z1 > 0.0:
            rows.append((x0, y0, x1, y1, z1))
    return np.array(rows, dtype=float).reshape(-1, 5)


def problem(obs: np.ndarray, xy) -> str | None:
    """Why a drone cannot stand at ``xy`` (inside a footprint, or closer than
    ``PAD_WALL_CLEARANCE_M`` to one), or None on free ground."""
    if len(obs) == 0:
        return None
    x, y = float(xy[0]), float(xy[1])
    dx = np.maximum(np.maximum(obs[:, 0] - x, x - obs[:, 2]), 0.0)
    dy = np.maximum(np.maximum(obs[:, 1] - y, y - obs[:, 3]), 0.0)
    dist = np.hypot(dx, dy)
    i = int(np.argmin(dist))
    if dist[i] >= PAD_WALL_CLEARANCE_M:
        return None
    x0, y0, x1, y1, top = obs[i]
    where = (f"obstacle {i} (x {x0:.1f}..{x1:.1f} m, y {y0:.1f}..{y1:.1f} m, "
             f"{top:.1f} m tall)")
    if dist[i] == 0.0:
        return f"inside {where}"
    return (f"{dist[i]:.2f} m from the wall of {where}, closer than "
            f"PAD_WALL_CLEARANCE_M = {PAD_WALL_CLEARANCE_M:g} m (on a roof edge or against "
            f"the wall)")


def free_pad(obs: np.ndarray, xy, taken=(), clearance: float = 2.0):
    """The free point nearest ``xy`` (itself when free), at least ``clearance`` from
    every pad in ``taken``; None when none lies within ``SEARCH_RADIUS_M``."""
    def ok(p):
        return problem(obs, p) is None and all(math.dist(p, q) >= clearance for q in taken)
    if ok(xy):
        return (float(xy[0]), float(xy[1]))
    n = int(SEARCH_RADIUS_M / SEARCH_STEP_M)
    for r in range(1, n + 1):                       # rings of growing radius, nearest first
        ring = []
        for i in range(-r, r + 1):
            for j in (-r, r):
                ring += [(i, j), (j, i)]
        ring.sort(key=lambda ij: (ij[0] ** 2 + ij[1] ** 2, ij))
        for i, j in ring:
            p = (float(xy[0]) + i * SEARCH_STEP_M, float(xy[1]) + j * SEARCH_STEP_M)
            if ok(p):
                return p
    return None


__all__ = ["PAD_WALL_CLEARANCE_M", "free_pad", "obstacles", "problem"]
