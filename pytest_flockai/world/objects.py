"""The objects the camera truth knows, one table per world: people, then vehicles.

For every object the table holds its class, its centre, the vertices of its
geometry (the tight image box of an object is the box of its projected
vertices: exact for the convex parts the figures are made of), sample points
spread through its volume (its visible fraction is the share of them a camera
sees) and the axis-aligned boxes by which it hides other objects.

Geometry (metres; a figure stands on the ground at its feet position):

- person: an octagonal torso prism (radius ``PERSON_RADIUS``) and a low-poly head
  sphere (``HEAD_RADIUS``), 1.7 m tall (the figures of ``World.urban``);
- vehicle: a compact car, 4.3 m x 1.8 m x 1.46 m (Volkswagen Golf 8 technical data:
  4284 x 1789 x 1456 mm), as a body box from 0.15 m to 0.95 m over the ground
  and a cabin (the glasshouse) box on top, 2.3 m x 1.6 m, set 0.2 m back.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .truth import CLASSES

PERSON_HEIGHT = 1.7          # m, adult figure
PERSON_RADIUS = 0.22         # m, torso prism
HEAD_RADIUS = 0.12           # m
PERSON, VEHICLE = CLASSES.index("person"), CLASSES.index("vehicle")

CAR_LENGTH, CAR_WIDTH, CAR_HEIGHT = 4.3, 1.8, 1.46
#: (centre x along the car, half length, half width, z0, z1) of the body and the cabin
CAR_BOXES = ((0.0, CAR_LENGTH / 2, CAR_WIDTH / 2, 0.15, 0.95),
             (-0.2, 1.15, 0.8, 0.95, CAR_HEIGHT))


def prism(n, r, z0, z1):
    """(vertices, faces) of an n-gon prism around the z axis, outward faces."""
    a = 2 * np.pi * (np.arange(n) + 0.5) / n
    ring = np.column_stack([r * np.cos(a), r * np.sin(a)])
    v = np.vstack([np.column_stack([ring, np.full(n, z0)]), np.column_stack([ring, np.full(n, z1)]),
                   [[0, 0, z0], [0, 0, z1]]])
    f = []
    for i in range(n):
        j = (i + 1) % n
        f += [(i, j, n + j), (i, n + j, n + i), (2 * n, j, i), (2 * n + 1, n + i, n + j)]
    return v, np.array(f)


def sphere(n, rings, r, zc):
    """(vertices, faces) of a low-poly UV sphere centred at (0, 0, zc)."""
    v = [[0, 0, zc - r], [0, 0, zc + r]]
    for k in range(1, rings):
        th = np.pi * k / rings - np.pi / 2
        for i in range(n):
            a = 2 * np.pi * i / n
            v.append([r * np.cos(th) * np.cos(a), r * np.cos(th) * np.sin(a), zc + r * np.sin(th)])
    f = []

    def idx(k, i):
        return 2 + (k - 1) * n + (i % n)
    for i in range(n):
        f.append((0, idx(1, i + 1), idx(1, i)))
        f.append((1, idx(rings - 1, i), idx(rings - 1, i + 1)))
        for k in range(1, rings - 1):
            f += [(idx(k, i), idx(k, i + 1), idx(k + 1, i + 1)), (idx(k, i), idx(k + 1, i + 1), idx(k + 1, i))]
    return np.array(v, dtype=float), np.array(f)


def box(cx, hx, hy, z0, z1):
    """(vertices, faces) of an axis-aligned box along the car's x axis."""
    x0, x1 = cx - hx, cx + hx
    v = np.array([[x, y, z] for z in (z0, z1) for y in (-hy, hy) for x in (x0, x1)], dtype=float)
    f = np.array([(0, 2, 3), (0, 3, 1), (4, 5, 7), (4, 7, 6), (0, 1, 5), (0, 5, 4),
                  (2, 6, 7), (2, 7, 3), (0, 4, 6), (0, 6, 2), (1, 3, 7), (1, 7, 5)])
    return v, f


TORSO = prism(8, PERSON_RADIUS, 0.0, PERSON_HEIGHT - 2 * HEAD_RADIUS - 0.02)
HEAD = sphere(8, 4, HEAD_RADIUS, PERSON_HEIGHT - HEAD_RADIUS)
CAR_BODY = box(*CAR_BOXES[0])
CAR_CABIN = box(*CAR_BOXES[1])


def _person_samples():
    """Points through a figure's volume: rings of 8 at the hips and the chest, the
    axis at the knees and the shoulders, and the head."""
    r = 0.7 * PERSON_RADIUS
    ring = [(r * math.cos(a), r * math.sin(a)) for a in (np.arange(8) + 0.5) * math.pi / 4]
    pts = [(x, y, z) for z in (0.6, 1.1) for x, y in ring]
    pts += [(0.0, 0.0, 0.3), (0.0, 0.0, 1.35), (0.0, 0.0, PERSON_HEIGHT - HEAD_RADIUS)]
    return np.array(pts)


def _car_samples():
    """Points through a car's volume: a 3 x 3 grid at mid-body and under the roof."""
    pts = [(x, y, 0.6) for x in (-1.6, 0.0, 1.6) for y in (-0.6, 0.0, 0.6)]
    pts += [(x, y, 1.3) for x in (-0.9, 0.5) for y in (-0.45, 0.45)]
    return np.array(pts)


PERSON_VERTS = np.vstack([TORSO[0][:-2], HEAD[0]])         # hull extremes (no cap centres)
CAR_VERTS = np.vstack([CAR_BODY[0], CAR_CABIN[0]])
PERSON_SAMPLES, CAR_SAMPLES = _person_samples(), _car_samples()


def _rotate(points, yaw):
    """points (P, 3) of a template turned by yaw (rad, counter-clockwise from east)."""
    c, s = math.cos(yaw), math.sin(yaw)
    p = np.asarray(points, dtype=float)
    return np.column_stack([c * p[:, 0] - s * p[:, 1], s * p[:, 0] + c * p[:, 1], p[:, 2]])


def _pad(rows, n):
    """Stack per-object point sets (P_i, 3) into (N, n, 3), padding with each set's first point."""
    out = np.empty((len(rows), n, 3))
    for i, r in enumerate(rows):
        out[i, :len(r)] = r
        out[i, len(r):] = r[0]
    return out


@dataclass
class ObjectTable:
    """Per object (N rows): ``cls``, ``centre`` (N, 3), ``verts`` (N, V, 3),
    ``samples`` (N, S, 3) with ``sample_w`` (N, S) 1 for a real sample and 0
    for padding, and ``boxes`` (B, 6) occluder boxes owned by ``box_owner`` (B,)."""

    cls: np.ndarray
    centre: np.ndarray
    verts: np.ndarray
    samples: np.ndarray
    sample_w: np.ndarray
    boxes: np.ndarray
    box_owner: np.ndarray

    def __len__(self) -> int:
        return int(len(self.cls))

    @classmethod
    def build(cls, people=(), vehicles=()) -> "ObjectTable":
        """people: (N, 3) feet positions; vehicles: (M, 4) rows (x, y, z, yaw)."""
        people = np.asarray(people, dtype=float).reshape(-1, 3)
        vehicles = np.asarray(vehicles, dtype=float).reshape(-1, 4)
        verts, samples, boxes, owner = [], [], [], []
        for i, p in enumerate(people):
            verts.append(PERSON_VERTS + p)
            samples.append(PERSON_SAMPLES + p)
            boxes.append([p[0] - PERSON_RADIUS, p[1] - PERSON_RADIUS, p[2],
                          p[0] + PERSON_RADIUS, p[1] + PERSON_RADIUS, p[2] + PERSON_HEIGHT])
            owner.append(i)
        for j, (x, y, z, yaw) in enumerate(vehicles):
            at = np.array([x, y, z])
            verts.append(_rotate(CAR_VERTS, yaw) + at)
            samples.append(_rotate(CAR_SAMPLES, yaw) + at)
            for cx, hx, hy, z0, z1 in CAR_BOXES:
                corners = _rotate(np.array([[cx - hx, -hy, z0], [cx + hx, hy, z1]]), yaw) + at
                boxes.append([*corners.min(axis=0), *corners.max(axis=0)])
                owner.append(len(people) + j)
        n = len(people) + len(vehicles)
        nv = max(len(PERSON_VERTS), len(CAR_VERTS))
        ns = max(len(PERSON_SAMPLES), len(CAR_SAMPLES))
        w = np.zeros((n, ns))
        for i, s in enumerate(samples):
            w[i, :len(s)] = 1.0
        kinds = np.r_[np.full(len(people), PERSON), np.full(len(vehicles), VEHICLE)].astype(int)
        centre = np.vstack([people + (0, 0, PERSON_HEIGHT / 2),
                            vehicles[:, :3] + (0, 0, CAR_HEIGHT / 2)]) if n else np.zeros((0, 3))
        return cls(kinds, centre, _pad(verts, nv) if n else np.zeros((0, nv, 3)),
                   _pad(samples, ns) if n else np.zeros((0, ns, 3)), w,
                   np.asarray(boxes, dtype=float).reshape(-1, 6), np.asarray(owner, dtype=int))
