"""Ground truth: which people a camera sees, and where in the image.

Pinhole projection with MuJoCo's camera convention: a camera frame
``cam_mat`` (3x3, columns = camera x, y, z in world coordinates, as
``MjData.cam_xmat``) looks along its -z axis with y up in the image and x to
the right. With the vertical field of view ``fovy`` and an image of
``width x height`` pixels, the focal length in pixels is
``f = (height / 2) / tan(fovy / 2)`` (square pixels, as MuJoCo renders, the
horizontal extent following the aspect ratio) and a point at camera
coordinates (x, y, z), z < 0, lands at::

    u = width / 2  + f * x / -z        (column, 0 = left edge)
    v = height / 2 - f * y / -z        (row, 0 = top edge)

A point is *in view* when it is in front of the camera and 0 <= u < width,
0 <= v < height; the pixel that shows it is (floor(v), floor(u)).

Occlusion: ``visible_people`` can drop people hidden behind axis-aligned
boxes (``occluders``, the urban world's buildings) with a vectorised
slab test of the segment camera -> person. People do not occlude each other,
and geometry of ``World.from_mjcf`` scenes other than axis-aligned boxes does
not occlude (documented limitation).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np


def gimbal_pose(pos, yaw: float, pitch_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """(cam_pos, cam_mat) of a camera at ``pos`` levelled by a gimbal.

    The camera keeps its pitch relative to the horizon (-90 = straight down)
    and turns with the drone's yaw (rad, counter-clockwise from east, the
    telemetry convention); the drone's roll and pitch do not reach it. Looking
    straight down, the top of the image points where the drone's nose points.
    """
    p = math.radians(pitch_deg)
    cp, sp = math.cos(p), math.sin(p)
    cy, sy = math.cos(yaw), math.sin(yaw)
    fx, fy, fz = cp * cy, cp * sy, sp
    ux, uy, uz = -sp * cy, -sp * sy, cp
    # columns: right = fwd x up, up, -fwd (written out: np.cross costs ~20x more here)
    mat = np.array([[fy * uz - fz * uy, ux, -fx], [fz * ux - fx * uz, uy, -fy],
                    [fx * uy - fy * ux, uz, -fz]])
    return np.asarray(pos, dtype=float).reshape(3), mat


def focal_px(fov_deg: float, height: int) -> float:
    """Focal length in pixels of a camera with vertical field of view ``fov_deg``."""
    return 0.5 * height / math.tan(math.radians(fov_deg) / 2.0)


def project(points, cam_pos, cam_mat, fov_deg: float, width: int, height: int):
    """(uv (N, 2), depth (N,)): pixel coordinates and distance along the view axis."""
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    R = np.asarray(cam_mat, dtype=float).reshape(3, 3)
    c = (pts - np.asarray(cam_pos, dtype=float).reshape(1, 3)) @ R   # camera coordinates
    depth = -c[:, 2]
    f = focal_px(fov_deg, height)
    with np.errstate(divide="ignore", invalid="ignore"):
        u = 0.5 * width + f * c[:, 0] / depth
        v = 0.5 * height - f * c[:, 1] / depth
    return np.column_stack([u, v]), depth


def segment_hits(cam_pos, points, boxes) -> np.ndarray:
    """(N, M) bool: the segment cam_pos -> point crosses box m (slab test).

    boxes: (M, 6) rows (xmin, ymin, zmin, xmax, ymax, zmax). A point inside a
    box counts as crossing it.
    """
    pts = np.asarray(points, dtype=float).reshape(-1, 3)
    b = np.asarray(boxes, dtype=float).reshape(-1, 6)
    if len(pts) == 0 or len(b) == 0:
        return np.zeros((len(pts), len(b)), dtype=bool)
    o = np.asarray(cam_pos, dtype=float).reshape(1, 1, 3)
    d = pts[:, None, :] - o                        # (N, 1, 3), segment t in [0, 1]
    lo, hi = b[None, :, :3], b[None, :, 3:]
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / d
        t1 = (lo - o) * inv
        t2 = (hi - o) * inv
    tmin = np.where(np.isnan(t1), -np.inf, np.minimum(t1, t2))
    tmax = np.where(np.isnan(t1), np.inf, np.maximum(t1, t2))
    # parallel to a slab and outside it: never inside
    par = (d == 0.0) & ((o < lo) | (o > hi))
    enter = tmin.max(axis=2)
    leave = tmax.min(axis=2)
    return (enter <= leave) & (leave >= 0.0) & (enter <= 1.0) & ~par.any(axis=2)


def occluded(cam_pos, points, boxes) -> np.ndarray:
    """Mask (N,): the segment cam_pos -> point crosses one of the boxes (M, 6)."""
    return np.asarray(segment_hits(cam_pos, points, boxes).any(axis=1))


def visible_people(world_people, cam_pos, cam_mat, fov_deg: float, width: int, height: int, *,
                   occluders=None, near: float = 0.05):
    """(indices (K,), uv (K, 2)): people whose point projects inside the image.

    world_people: (N, 3) points to project (``World.truth_points()``: the
    centre of each figure). occluders: optional (M, 6) boxes hiding people.
    """
    pts = np.asarray(world_people, dtype=float).reshape(-1, 3)
    uv, depth = project(pts, cam_pos, cam_mat, fov_deg, width, height)
    ok = ((depth > near) & (uv[:, 0] >= 0.0) & (uv[:, 0] < width)
          & (uv[:, 1] >= 0.0) & (uv[:, 1] < height))
    idx = np.flatnonzero(ok)
    if occluders is not None and len(idx):
        idx = idx[~occluded(cam_pos, pts[idx], occluders)]
    return idx, uv[idx]


#: object classes of the simulated worlds; a COCO category id is the index + 1
CLASSES = ("person", "vehicle")


def _empty(shape, dtype=float):
    return np.zeros(shape, dtype=dtype)


@dataclass
class Objects:
    """Per-object ground truth of one frame: K objects, one row each.

    ids: (K,) int, the object's index in its world's object table (stable
    over a flight, so an object can be followed from frame to frame; -1 when
    unknown, e.g. labels read from a file); cls: (K,) int, an index into
    ``classes``; boxes: (K, 4) float, the tight box ``x0, y0, x1, y1`` in
    pixels (origin top-left, x1/y1 exclusive edges), clipped to the image;
    visible: (K,) visible fraction in [0, 1] (occlusion by buildings and other
    objects, and the part outside the image); distance_m: (K,) camera to
    object centre; gsd_m: (K,) ground sample distance at the object, metres
    per pixel (NaN when unknown).
    """

    ids: np.ndarray = field(default_factory=lambda: _empty(0, int))
    cls: np.ndarray = field(default_factory=lambda: _empty(0, int))
    boxes: np.ndarray = field(default_factory=lambda: _empty((0, 4)))
    visible: np.ndarray = field(default_factory=lambda: _empty(0))
    distance_m: np.ndarray = field(default_factory=lambda: _empty(0))
    gsd_m: np.ndarray = field(default_factory=lambda: _empty(0))
    classes: tuple = CLASSES

    def __len__(self) -> int:
        return int(len(self.cls))


@dataclass
class Truth:
    """Ground truth of one camera frame.

    t: simulated time (s); indices: which of ``world.people`` are in view;
    pixels: (K, 2) their (u, v) pixel coordinates (u = column, v = row,
    origin at the top-left corner); cam_pos / cam_mat: the camera pose;
    objects: per-object truth (boxes, classes, visibility) of every object in view.
    """

    t: float
    indices: np.ndarray
    pixels: np.ndarray
    cam_pos: np.ndarray = field(default_factory=lambda: np.zeros(3))
    cam_mat: np.ndarray = field(default_factory=lambda: np.eye(3))
    objects: Objects = field(default_factory=Objects)
    #: (du, dv) pixels of motion blur in this frame (imaging conditions), (0, 0) without
    blur_px: tuple = (0.0, 0.0)
    #: (du, dv) pixels the image moves over the rolling-shutter readout, (0, 0) without;
    #: the object boxes already include the shift of their centre row
    skew_px: tuple = (0.0, 0.0)

    @property
    def count(self) -> int:
        """How many objects are visible."""
        return int(len(self.indices))

    def to_dict(self) -> dict:
        """JSON-ready description for the flight's scenario."""
        return {"t": float(self.t), "count": self.count,
                "indices": [int(i) for i in self.indices],
                "pixels": [[round(float(u), 2), round(float(v), 2)] for u, v in self.pixels],
                "cam_pos": [float(x) for x in self.cam_pos]}


def _cull_boxes(boxes, lo_xy, hi_xy):
    """The boxes whose xy extent meets the rectangle [lo_xy, hi_xy]."""
    b = np.asarray(boxes, dtype=float).reshape(-1, 6)
    keep = ((b[:, 0] <= hi_xy[0]) & (b[:, 3] >= lo_xy[0]) & (b[:, 1] <= hi_xy[1])
            & (b[:, 4] >= lo_xy[1]))
    return b[keep], keep


def object_truth(table, cam_pos, cam_mat, fov_deg: float, width: int, height: int, *,
                 occluders=None, near: float = 0.05, classes=CLASSES) -> Objects:
    """Per-object truth of one view: every object of ``table`` (a world's
    ``ObjectTable``) whose box meets the image.

    - box: the tight box of the projected vertices of the object's geometry,
      clipped to the image (exact for its convex parts);
    - visible: the share of the object's volume sample points that project
      inside the image and whose line of sight to the camera crosses no
      building (``occluders``) and no other object's box;
    - distance_m: camera to object centre; gsd_m: metres per pixel at the
      object's depth along the view axis (depth / focal length in pixels).
    """
    if table is None or len(table) == 0:
        return Objects(classes=tuple(classes))
    cam_pos = np.asarray(cam_pos, dtype=float).reshape(3)
    f = focal_px(fov_deg, height)
    uv, depth = project(table.centre, cam_pos, cam_mat, fov_deg, width, height)
    reach = f * 3.0 / np.maximum(depth, near)                  # 3 m around the centre, in px
    cand = np.flatnonzero((depth > near) & (uv[:, 0] > -reach) & (uv[:, 0] < width + reach)
                          & (uv[:, 1] > -reach) & (uv[:, 1] < height + reach))
    if len(cand) == 0:
        return Objects(classes=tuple(classes))
    k, nv = len(cand), table.verts.shape[1]
    vuv, vdepth = project(table.verts[cand].reshape(-1, 3), cam_pos, cam_mat, fov_deg, width, height)
    vuv, vdepth = vuv.reshape(k, nv, 2), vdepth.reshape(k, nv)
    front = (vdepth > near).all(axis=1)
    lo, hi = vuv.min(axis=1), vuv.max(axis=1)
    box = np.column_stack([np.clip(lo[:, 0], 0, width), np.clip(lo[:, 1], 0, height),
                           np.clip(hi[:, 0], 0, width), np.clip(hi[:, 1], 0, height)])
    ok = front & (box[:, 2] > box[:, 0]) & (box[:, 3] > box[:, 1])
    cand, box = cand[ok], box[ok]
    if len(cand) == 0:
        return Objects(classes=tuple(classes))
    vis = _visible_fraction(table, cand, cam_pos, cam_mat, fov_deg, width, height, occluders, near)
    dist = np.linalg.norm(table.centre[cand] - cam_pos, axis=1)
    return Objects(ids=cand.astype(int), cls=table.cls[cand].astype(int), boxes=box, visible=vis,
                   distance_m=dist, gsd_m=depth[cand] / f, classes=tuple(classes))


def _visible_fraction(table, cand, cam_pos, cam_mat, fov_deg, width, height, occluders, near):
    k, ns = len(cand), table.samples.shape[1]
    pts = table.samples[cand].reshape(-1, 3)
    w = table.sample_w[cand].reshape(-1)
    suv, sdepth = project(pts, cam_pos, cam_mat, fov_deg, width, height)
    seen = ((sdepth > near) & (suv[:, 0] >= 0) & (suv[:, 0] < width) & (suv[:, 1] >= 0)
            & (suv[:, 1] < height) & (w > 0))
    lo_xy = np.minimum(pts[:, :2].min(axis=0), cam_pos[:2])
    hi_xy = np.maximum(pts[:, :2].max(axis=0), cam_pos[:2])
    if occluders is not None and len(occluders) and seen.any():
        bld, _ = _cull_boxes(occluders, lo_xy, hi_xy)
        idx = np.flatnonzero(seen)
        seen[idx[occluded(cam_pos, pts[idx], bld)]] = False
    in_view = np.isin(table.box_owner, cand)
    obox, owner = table.boxes[in_view], table.box_owner[in_view]
    if len(obox) > 1 and seen.any():
        _hide_behind_objects(seen, pts, np.repeat(cand, ns), obox, owner, cam_pos)
    return (seen.reshape(k, ns).sum(axis=1) / table.sample_w[cand].sum(axis=1)).astype(float)


def _hide_behind_objects(seen, pts, point_owner, obox, owner, cam_pos):
    """Clear ``seen`` for points whose line of sight crosses another object's box.

    A point inside another object's box is hidden by it only when that object is the
    clearly bigger body (its bounding volume over ``ENGULF_RATIO`` times the point's
    object's: a person under a car is hidden from above). Bodies of one size at one
    spot (two walkers meeting, a crowd, two cars) overlap without hiding each other:
    each keeps the points the other's box does not cover from the camera.

    The objects are low (a few metres), so only the stretch of a sight line below
    the tallest box can meet one: the boxes tested against a point are those whose
    xy extent meets that stretch's xy extent, found through a uniform xy grid
    (``_near_pairs``), so the cost grows with the pairs that are near, not with
    points x boxes (thousands of walkers in view stay within a few MiB per chunk)."""
    idx = np.flatnonzero(seen)
    top = obox[:, 5].max()
    n_obj = int(max(owner.max(), point_owner.max())) + 1
    lo3, hi3 = np.full((n_obj, 3), np.inf), np.full((n_obj, 3), -np.inf)
    np.minimum.at(lo3, owner, obox[:, :3])
    np.maximum.at(hi3, owner, obox[:, 3:])
    vol = np.where(np.isfinite(lo3).all(axis=1), np.prod(np.maximum(hi3 - lo3, 0.0), axis=1), 0.0)
    for c0 in range(0, len(idx), _CHUNK):
        ci = idx[c0:c0 + _CHUNK]
        p = pts[ci]
        dz = cam_pos[2] - p[:, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.clip(np.where(dz > 0, (top - p[:, 2]) / dz, 1.0), 0.0, 1.0)
        q = p[:, :2] + t[:, None] * (cam_pos[:2] - p[:, :2])   # where the line rises above `top`
        lo, hi = np.minimum(p[:, :2], q), np.maximum(p[:, :2], q)
        pi, bi = _near_pairs(lo, hi, obox)
        b, mine, other = obox[bi], point_owner[ci][pi], owner[bi]
        inside = ((p[pi] >= b[:, :3]) & (p[pi] <= b[:, 3:])).all(axis=1)
        keep = ((b[:, 0] <= hi[pi, 0]) & (b[:, 3] >= lo[pi, 0]) & (b[:, 1] <= hi[pi, 1])
                & (b[:, 4] >= lo[pi, 1]) & (other != mine)
                & (~inside | (vol[other] > ENGULF_RATIO * vol[mine])))
        pi, b = pi[keep], b[keep]
        hit = _pair_hits(cam_pos, p[pi], b)
        seen[ci[np.unique(pi[hit])]] = False


#: how much bigger (bounding volume) a body must be to hide the points of another that
#: lie inside its box (a car over a person: ~20x); bodies closer in size never do
ENGULF_RATIO = 2.0
#: sight-line points handled at once by the occlusion test (bounds its memory)
_CHUNK = 20_000


def _near_pairs(lo, hi, boxes):
    """(point index, box index) of every point rectangle [lo, hi] (N, 2) and box (M, 6)
    sharing a cell of a uniform xy grid (cells as wide as the widest box), each once."""
    ext = np.maximum(boxes[:, 3] - boxes[:, 0], boxes[:, 4] - boxes[:, 1])
    cell = max(float(ext.max()), 0.25)
    ox = min(float(lo[:, 0].min()), float(boxes[:, 0].min()))
    oy = min(float(lo[:, 1].min()), float(boxes[:, 1].min()))

    def span(a0, a1, o):
        return (np.floor((a0 - o) / cell).astype(np.int64),
                np.floor((a1 - o) / cell).astype(np.int64))

    bx0, bx1 = span(boxes[:, 0], boxes[:, 3], ox)
    by0, by1 = span(boxes[:, 1], boxes[:, 4], oy)
    px0, px1 = span(lo[:, 0], hi[:, 0], ox)
    py0, py1 = span(lo[:, 1], hi[:, 1], oy)
    ny = int(max(by1.max(), py1.max())) + 1
    bcell, bown = _cells(bx0, bx1, by0, by1, ny)
    order = np.argsort(bcell, kind="stable")
    bcell, bown = bcell[order], bown[order]
    pcell, pown = _cells(px0, px1, py0, py1, ny)
    start = np.searchsorted(bcell, pcell, side="left")
    cnt = np.searchsorted(bcell, pcell, side="right") - start
    pi = np.repeat(pown, cnt)
    k = np.arange(int(cnt.sum())) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    bi = bown[np.repeat(start, cnt) + k]
    code = np.unique(pi * len(boxes) + bi)
    return code // len(boxes), code % len(boxes)


def _cells(x0, x1, y0, y1, ny):
    """(cell id, owner) of every grid cell each rectangle [x0..x1] x [y0..y1] covers."""
    wy = y1 - y0 + 1
    n = (x1 - x0 + 1) * wy
    own = np.repeat(np.arange(len(x0), dtype=np.int64), n)
    k = np.arange(int(n.sum()), dtype=np.int64) - np.repeat(np.cumsum(n) - n, n)
    return (x0[own] + k // wy[own]) * ny + (y0[own] + k % wy[own]), own


def _pair_hits(cam_pos, p, b) -> np.ndarray:
    """(K,) bool: the segment cam_pos -> p[k] crosses box b[k] (the slab test of
    ``segment_hits``, one box per point)."""
    o = np.asarray(cam_pos, dtype=float).reshape(1, 3)
    d = p - o
    lo, hi = b[:, :3], b[:, 3:]
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / d
        t1 = (lo - o) * inv
        t2 = (hi - o) * inv
    tmin = np.where(np.isnan(t1), -np.inf, np.minimum(t1, t2))
    tmax = np.where(np.isnan(t1), np.inf, np.maximum(t1, t2))
    par = (d == 0.0) & ((o < lo) | (o > hi))
    enter, leave = tmin.max(axis=1), tmax.min(axis=1)
    return (enter <= leave) & (leave >= 0.0) & (enter <= 1.0) & ~par.any(axis=1)


class CameraModel:
    """Pinhole model of a camera: image size and vertical field of view."""

    def __init__(self, width: int, height: int, fov_deg: float):
        self.width, self.height, self.fov_deg = int(width), int(height), float(fov_deg)

    @property
    def focal_px(self) -> float:
        """Focal length in pixels."""
        return focal_px(self.fov_deg, self.height)

    def project(self, points, cam_pos, cam_mat) -> tuple[np.ndarray, np.ndarray]:
        """(uv (N, 2), depth (N,)) of ``points`` seen from this camera."""
        return project(points, cam_pos, cam_mat, self.fov_deg, self.width, self.height)

    def truth(self, t, points, cam_pos, cam_mat, occluders=None, objects=None) -> Truth:
        """The frame's truth: people in view (``points``) and, with ``objects`` (a
        world's ``ObjectTable``), every object's box, class and visibility."""
        idx, uv = visible_people(points, cam_pos, cam_mat, self.fov_deg, self.width, self.height,
                                 occluders=occluders)
        objs = object_truth(objects, cam_pos, cam_mat, self.fov_deg, self.width, self.height,
                            occluders=occluders)
        return Truth(float(t), idx, uv, np.array(cam_pos, dtype=float), np.array(cam_mat, dtype=float),
                     objs)
