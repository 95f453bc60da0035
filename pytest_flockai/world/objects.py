"""The objects the camera truth knows, one table per world: people, then vehicles.

For every object the table holds its class, its centre, the vertices of its
geometry (the tight image box of an object is the box of its projected
vertices: exact, since they are the vertices that are drawn), sample points
spread through its volume (its visible fraction is the share of them a camera
sees) and the axis-aligned boxes by which it hides other objects.

Geometry (metres; a figure stands on the ground at its feet position):

- person: the articulated figures of ``figures.py`` (legs, torso, arms, head,
  each in its own pose), or for ``figures="simple"`` worlds an octagonal torso
  prism (radius ``PERSON_RADIUS``) and a low-poly head sphere (``HEAD_RADIUS``),
  1.7 m tall; a person hides others by the axis-aligned box of its vertices;
- vehicle: a compact car, 4.3 m x 1.8 m x 1.46 m (Volkswagen Golf 8 technical data:
  4284 x 1789 x 1456 mm): with articulated figures, painted body and roof, glasshouse
  and tyres (``figures.CAR``); with simple figures, the first release's body box from
  0.15 m to 0.95 m and a glass cabin box on top (``SIMPLE_CAR_BOXES``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .figures import CAR as CAR_MESHES
from .figures import box, prism, sphere
from .truth import CLASSES

PERSON_HEIGHT = 1.7          # m, adult figure
PERSON_RADIUS = 0.22         # m, torso prism of the simple figure
HEAD_RADIUS = 0.12           # m, head of the simple figure
PERSON, VEHICLE = CLASSES.index("person"), CLASSES.index("vehicle")

CAR_LENGTH, CAR_WIDTH, CAR_HEIGHT = 4.3, 1.8, 1.46
#: (centre x along the car, half length, half width, z0, z1) of the boxes by which a car
#: hides other objects: the body (tyres included) and the cabin
CAR_BOXES = ((0.0, CAR_LENGTH / 2, CAR_WIDTH / 2, 0.0, 0.95),
             (-0.25, 1.2, 0.8, 0.95, CAR_HEIGHT))
#: the simple car's geometry (and occluder boxes): body, then the glass cabin, 2.3 x 1.6 m
SIMPLE_CAR_BOXES = ((0.0, CAR_LENGTH / 2, CAR_WIDTH / 2, 0.15, 0.95),
                    (-0.2, 1.15, 0.8, 0.95, CAR_HEIGHT))

#: the simple figure (``figures="simple"``)
TORSO = prism(8, PERSON_RADIUS, 0.0, PERSON_HEIGHT - 2 * HEAD_RADIUS - 0.02)
HEAD = sphere(8, 4, HEAD_RADIUS, PERSON_HEIGHT - HEAD_RADIUS)


def _person_samples():
    """Points through a simple figure's volume: rings of 8 at the hips and the
    chest, the axis at the knees and the shoulders, and the head."""
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
CAR_VERTS = np.vstack([m[0] for m in CAR_MESHES.values()])
SIMPLE_CAR = (box(*SIMPLE_CAR_BOXES[0]), box(*SIMPLE_CAR_BOXES[1]))
SIMPLE_CAR_VERTS = np.vstack([m[0] for m in SIMPLE_CAR])
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
    def build(cls, people=(), vehicles=(), shapes=None) -> ObjectTable:
        """people: (N, 3) feet positions; vehicles: (M, 4) rows (x, y, z, yaw);
        shapes: None (simple figures and cars) or, per person, (vertices (V, 3),
        samples (S, 3)) relative to the feet (``figures.person`` in its pose), with
        the articulated cars."""
        people = np.asarray(people, dtype=float).reshape(-1, 3)
        vehicles = np.asarray(vehicles, dtype=float).reshape(-1, 4)
        verts, samples, boxes, owner = [], [], [], []
        for i, p in enumerate(people):
            v, s = (PERSON_VERTS, PERSON_SAMPLES) if shapes is None else shapes[i]
            verts.append(v + p)
            samples.append(s + p)
            if shapes is None:
                boxes.append([p[0] - PERSON_RADIUS, p[1] - PERSON_RADIUS, p[2],
                              p[0] + PERSON_RADIUS, p[1] + PERSON_RADIUS, p[2] + PERSON_HEIGHT])
            else:
                boxes.append([*verts[-1].min(axis=0), *verts[-1].max(axis=0)])
            owner.append(i)
        car_verts, car_boxes = ((SIMPLE_CAR_VERTS, SIMPLE_CAR_BOXES) if shapes is None
                                else (CAR_VERTS, CAR_BOXES))
        for j, (x, y, z, yaw) in enumerate(vehicles):
            at = np.array([x, y, z])
            verts.append(_rotate(car_verts, yaw) + at)
            samples.append(_rotate(CAR_SAMPLES, yaw) + at)
            for cx, hx, hy, z0, z1 in car_boxes:
                corners = _rotate(np.array([[cx - hx, -hy, z0], [cx + hx, hy, z1]]), yaw) + at
                boxes.append([*corners.min(axis=0), *corners.max(axis=0)])
                owner.append(len(people) + j)
        n = len(people) + len(vehicles)
        nv = max([len(car_verts)] + [len(v) for v in verts])
        ns = max([len(CAR_SAMPLES)] + [len(s) for s in samples])
        w = np.zeros((n, ns))
        for i, s in enumerate(samples):
            w[i, :len(s)] = 1.0
        kinds = np.r_[np.full(len(people), PERSON), np.full(len(vehicles), VEHICLE)].astype(int)
        centre = np.vstack([people + (0, 0, PERSON_HEIGHT / 2),
                            vehicles[:, :3] + (0, 0, CAR_HEIGHT / 2)]) if n else np.zeros((0, 3))
        return cls(kinds, centre, _pad(verts, nv) if n else np.zeros((0, nv, 3)),
                   _pad(samples, ns) if n else np.zeros((0, ns, 3)), w,
                   np.asarray(boxes, dtype=float).reshape(-1, 6), np.asarray(owner, dtype=int))
