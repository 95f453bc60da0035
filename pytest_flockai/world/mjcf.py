"""People and occluders found in a user's MJCF scene (``World.from_mjcf``)."""

from __future__ import annotations

from .._mujoco import mujoco
import numpy as np


def find_people(model) -> np.ndarray:
    d = mujoco.MjData(model)
    mujoco.mj_forward(model, d)
    pos = []
    for b in range(1, model.nbody):
        if (model.body(b).name or "").rsplit("/", 1)[-1].startswith("person"):
            pos.append(d.xpos[b].copy())
    if pos:
        return np.array(pos)
    groups: dict[str, list] = {}
    for g in range(model.ngeom):
        name = model.geom(g).name or ""
        base = name.rsplit("/", 1)[-1]
        if base.startswith("person"):
            groups.setdefault(base.split("_", 1)[0], []).append(d.geom_xpos[g])
    return np.array([np.mean(v, axis=0) for v in groups.values()]).reshape(-1, 3)


def box_occluders(model) -> np.ndarray:
    """Axis-aligned (in world) box geoms that are not people: (M, 6) AABBs."""
    d = mujoco.MjData(model)
    mujoco.mj_forward(model, d)
    rows = []
    for g in range(model.ngeom):
        if model.geom_type[g] != mujoco.mjtGeom.mjGEOM_BOX:
            continue
        if (model.geom(g).name or "").rsplit("/", 1)[-1].startswith("person"):
            continue
        R = np.abs(d.geom_xmat[g].reshape(3, 3))
        if not np.allclose(np.sort(R, axis=0)[-1], 1.0, atol=1e-6):
            continue   # rotated about a non-principal axis: not an axis-aligned box
        half = R @ model.geom_size[g]
        c = d.geom_xpos[g]
        rows.append([*(c - half), *(c + half)])
    return np.array(rows, dtype=float).reshape(-1, 6)
