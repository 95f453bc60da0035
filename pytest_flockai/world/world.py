"""Worlds: the scene the drone flies in.

``World.empty()`` is an unbounded flat ground. Urban worlds with buildings and
people (issue 6) add themselves to the MuJoCo spec through ``add_to_spec``.
"""

from __future__ import annotations

import numpy as np

import mujoco


class World:
    def __init__(self, name: str = "empty"):
        self.name = name
        self.people = np.zeros((0, 3))

    @classmethod
    def empty(cls) -> "World":
        return cls("empty")

    def add_to_spec(self, spec: "mujoco.MjSpec") -> None:
        spec.worldbody.add_geom(name="ground", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 1],
                                rgba=[0.45, 0.5, 0.4, 1])

    def to_dict(self) -> dict:
        return {"name": self.name, "people": int(len(self.people))}

    def __repr__(self):
        return f"World({self.name!r})"
