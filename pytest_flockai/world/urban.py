"""Procedural urban layout: a street grid, box buildings in the blocks, people.

Pure numpy (no MuJoCo): ``layout(...)`` returns the streets, buildings and
people of an urban world; ``World.urban`` validates the arguments and turns the
layout into MjSpec geoms. Every draw comes from ``numpy.random.SeedSequence(seed)``
with one child stream per concern (buildings, scattered people, each crowd,
colours), so adding people never moves a building and adding a crowd never
moves the scattered people.

Geometry (world frame: x east, y north, z up, home at (0, 0, 0)):

- the area is ``[-W/2, W/2] x [-H/2, H/2]``; streets run along x and y every
  ``BLOCK_PITCH`` m, with a street through home;
- each block is split into 1, 2 or 4 lots; a lot gets a building with
  probability ``building_density``, set back 1-3 m from the lot edges, height
  6-45 m (mid-rise city); no building comes within ``clear_radius`` of home
  (take-off and landing) nor within two spreads (+2 m) of a crowd centre (the
  crowd gathers on a square); buildings never overlap each other (each one is
  inside its own lot);
- people stand on the ground outside the buildings (0.5 m margin): scattered
  uniformly over the area, plus Gaussian clusters (per-axis standard deviation
  = spread) around each crowd centre.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import ConfigError
from .figures import draw_poses
from .objects import CAR_LENGTH, CAR_WIDTH

BLOCK_PITCH = 40.0        # m, street centre to street centre
STREET_WIDTH = 10.0       # m, carriageway plus sidewalks
PERSON_AREA_M2 = 0.5      # m^2 per person: the densest crowd a cluster may hold
PERSON_MARGIN = 0.5       # m kept between a person and a building wall
HEIGHT_RANGE = (6.0, 45.0)

# (streams of SeedSequence(seed)) -- fixed keys so streams never shift
_S_BUILDINGS, _S_SCATTER, _S_CROWDS, _S_COLOURS = range(4)
_S_VEHICLES = 5
_S_FIGURES = 6
#: m, lateral offsets of cars from a street's centre line: kerb parking and the two lanes
LANES = (-2.6, -1.0, 1.0, 2.6)


def _rng(seed: int, *key: int) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=tuple(key)))


def crowd_capacity(spread: float) -> int:
    """Most people a cluster of this spread may hold: disc of radius 2 spreads / 0.5 m^2."""
    return int(math.pi * (2.0 * spread) ** 2 / PERSON_AREA_M2)


def _lot_distance(lot, x, y) -> float:
    """Distance from point (x, y) to the rectangle lot = (x0, y0, x1, y1)."""
    x0, y0, x1, y1 = lot
    dx = max(x0 - x, 0.0, x - x1)
    dy = max(y0 - y, 0.0, y - y1)
    return math.hypot(dx, dy)


def streets(size) -> list[tuple[float, float, float, float]]:
    """Street rectangles (x0, y0, x1, y1) clipped to the area."""
    W, H = size
    out = []
    for axis, (_half_along, half_across) in ((0, (W / 2, H / 2)), (1, (H / 2, W / 2))):
        k0 = math.ceil(-half_across / BLOCK_PITCH)
        k1 = math.floor(half_across / BLOCK_PITCH)
        for k in range(k0, k1 + 1):
            c = k * BLOCK_PITCH
            a0, a1 = max(c - STREET_WIDTH / 2, -half_across), min(c + STREET_WIDTH / 2, half_across)
            if a1 <= a0:
                continue
            if axis == 0:   # street along x at y = c
                out.append((-W / 2, a0, W / 2, a1))
            else:           # street along y at x = c
                out.append((a0, -H / 2, a1, H / 2))
    return out


def buildings(seed: int, size, *, density: float, clear_radius: float,
              max_height: float | None = None,
              keep_clear=()) -> np.ndarray:
    """Buildings as rows (cx, cy, hx, hy, height): centre, half sizes, height (m).

    keep_clear: (x, y, radius) discs no building may touch.
    """
    rng = _rng(seed, _S_BUILDINGS)
    W, H = size
    clears = [(0.0, 0.0, clear_radius)] + list(keep_clear)
    rows = []
    kx0, kx1 = math.floor(-W / 2 / BLOCK_PITCH), math.ceil(W / 2 / BLOCK_PITCH)
    ky0, ky1 = math.floor(-H / 2 / BLOCK_PITCH), math.ceil(H / 2 / BLOCK_PITCH)
    for i in range(kx0, kx1):
        for j in range(ky0, ky1):
            bx0 = max(i * BLOCK_PITCH + STREET_WIDTH / 2, -W / 2)
            bx1 = min((i + 1) * BLOCK_PITCH - STREET_WIDTH / 2, W / 2)
            by0 = max(j * BLOCK_PITCH + STREET_WIDTH / 2, -H / 2)
            by1 = min((j + 1) * BLOCK_PITCH - STREET_WIDTH / 2, H / 2)
            # the same number of draws for every block keeps the stream aligned
            split = rng.integers(0, 3)             # 0: one lot, 1: two, 2: four
            u = rng.random((4, 6))
            if bx1 - bx0 < 6.0 or by1 - by0 < 6.0:
                continue
            nx, ny = ((1, 1), (2, 1), (2, 2))[split]
            if split == 1 and u[0, 5] < 0.5:
                nx, ny = 1, 2
            lw, lh = (bx1 - bx0) / nx, (by1 - by0) / ny
            for a in range(nx):
                for b in range(ny):
                    r = u[a * ny + b]
                    if r[0] >= density:
                        continue
                    lot = (bx0 + a * lw, by0 + b * lh, bx0 + (a + 1) * lw, by0 + (b + 1) * lh)
                    sb = 1.0 + 2.0 * r[1:5]          # setbacks: west, east, south, north
                    x0, x1 = lot[0] + sb[0], lot[2] - sb[1]
                    y0, y1 = lot[1] + sb[2], lot[3] - sb[3]
                    if x1 - x0 < 3.0 or y1 - y0 < 3.0:
                        continue
                    if any(_lot_distance((x0, y0, x1, y1), cx, cy) < rad for cx, cy, rad in clears):
                        continue
                    top = HEIGHT_RANGE[1] if max_height is None else max(HEIGHT_RANGE[0], max_height)
                    h = HEIGHT_RANGE[0] + (top - HEIGHT_RANGE[0]) * r[5] ** 2
                    rows.append(((x0 + x1) / 2, (y0 + y1) / 2, (x1 - x0) / 2, (y1 - y0) / 2, h))
    return np.array(rows, dtype=float).reshape(-1, 5)


def inside_buildings(xy: np.ndarray, bld: np.ndarray, margin: float = PERSON_MARGIN) -> np.ndarray:
    """Boolean mask: which points (N, 2) are within ``margin`` of a building footprint."""
    if len(bld) == 0 or len(xy) == 0:
        return np.zeros(len(xy), dtype=bool)
    out = np.empty(len(xy), dtype=bool)
    step = max(1, _BLOCK // len(bld))      # points per block: a block is at most _BLOCK pairs
    for i in range(0, len(xy), step):
        p = xy[i:i + step]
        dx = np.abs(p[:, None, 0] - bld[None, :, 0]) - bld[None, :, 2]
        dy = np.abs(p[:, None, 1] - bld[None, :, 1]) - bld[None, :, 3]
        out[i:i + step] = ((dx < margin) & (dy < margin)).any(axis=1)
    return out


#: point-building pairs compared at once by ``inside_buildings`` (about 32 MB per array):
#: the whole points x buildings matrix of a large city would take gigabytes
_BLOCK = 4_000_000


def _place(rng, n, draw, bld, size, what) -> np.ndarray:
    """Rejection-sample n ground points with ``draw(rng, k) -> (k, 2)``; outside buildings."""
    W, H = size
    out = np.zeros((0, 2))
    tries = 0
    while len(out) < n:
        tries += 1
        if tries > 60:
            raise ConfigError(f"World.urban: could not place {what} outside the buildings "
                              f"(placed {len(out)} of {n}); allowed: fewer people, a larger "
                              f"spread or a lower building_density")
        k = max(16, 2 * (n - len(out)))
        p = draw(rng, k)
        ok = (np.abs(p[:, 0]) <= W / 2) & (np.abs(p[:, 1]) <= H / 2)
        p = p[ok]
        p = p[~inside_buildings(p, bld)]
        out = np.concatenate([out, p[: n - len(out)]])
    return out


def people(seed: int, size, scattered: int, crowds, bld: np.ndarray) -> np.ndarray:
    """Feet positions (N, 3): the scattered people first, then each crowd in order."""
    W, H = size
    parts = [_place(_rng(seed, _S_SCATTER), scattered,
                    lambda r, k: r.uniform((-W / 2, -H / 2), (W / 2, H / 2), size=(k, 2)),
                    bld, size, f"people = {scattered} scattered people")]
    for i, (cx, cy, count, spread) in enumerate(crowds):
        parts.append(_place(_rng(seed, _S_CROWDS, i), count,
                            lambda r, k, c=(cx, cy), s=spread: r.normal(c, s, size=(k, 2)),
                            bld, size, f"crowds[{i}] ({count} people)"))
    xy = np.concatenate(parts) if parts else np.zeros((0, 2))
    return np.column_stack([xy, np.zeros(len(xy))])


# clothing: saturated colours that stand out from asphalt, concrete and grass
CLOTHES = np.array([
    (0.85, 0.10, 0.10), (0.10, 0.25, 0.85), (0.95, 0.80, 0.10), (0.90, 0.45, 0.05),
    (0.55, 0.10, 0.70), (0.05, 0.65, 0.75), (0.90, 0.20, 0.55), (0.95, 0.95, 0.95),
    (0.15, 0.15, 0.18), (0.20, 0.70, 0.20), (0.60, 0.30, 0.10), (0.10, 0.45, 0.45),
])
SKIN = np.array([(0.98, 0.84, 0.72), (0.90, 0.72, 0.57), (0.76, 0.57, 0.42),
                 (0.55, 0.38, 0.26), (0.36, 0.24, 0.16)])
# trousers: denim blues, black, greys, khaki, brown, olive
TROUSERS = np.array([(0.16, 0.22, 0.40), (0.25, 0.33, 0.52), (0.08, 0.08, 0.09),
                     (0.35, 0.35, 0.37), (0.62, 0.56, 0.42), (0.36, 0.25, 0.16),
                     (0.30, 0.34, 0.20)])


def colours(seed: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(clothes index (N,), skin index (N,)) into CLOTHES and SKIN, drawn from the seed."""
    rng = _rng(seed, _S_COLOURS)
    return rng.integers(0, len(CLOTHES), n), rng.integers(0, len(SKIN), n)


def figure_draws(seed: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(poses (N, 7) as ``figures.draw_poses``, trousers index (N,)) from their own
    stream: articulated figures move no position and no other colour."""
    rng = _rng(seed, _S_FIGURES)
    return draw_poses(rng, n), rng.integers(0, len(TROUSERS), n)


# -- figures as merged meshes ----------------------------------------------------
# One mesh geom per colour (clothes palette + skin palette) holding every figure
# of that colour: the physics model then carries ~17 people geoms instead of two
# per person. MuJoCo computes the pose of every geom at every physics step, static
# or not: 300 figure geoms doubled the cost of mj_step (see benchmarks/camera.py).

def merged(template, positions):
    """(vertices (K*V, 3), faces (K*F, 3)): the template copied at each (x, y, z)."""
    v, f = template
    k = len(positions)
    verts = (v[None, :, :] + np.asarray(positions, dtype=float)[:, None, :]).reshape(-1, 3)
    faces = (f[None, :, :] + (np.arange(k) * len(v))[:, None, None]).reshape(-1, 3)
    return verts, faces


def vehicles(seed: int, size, n: int, bld: np.ndarray, people: np.ndarray,
             clear_radius: float) -> np.ndarray:
    """Cars (n, 4) rows (x, y, z, yaw) on the streets: parked at the kerbs and in the
    lanes, yaw along the street, none within ``clear_radius`` of home, on a person
    (0.5 m margin) or on another car; drawn from their own stream."""
    rng = _rng(seed, _S_VEHICLES)
    sts = streets(size)
    out: list = []
    half = np.array([CAR_LENGTH / 2 + 0.5, CAR_WIDTH / 2 + 0.5])
    tries = 0
    while len(out) < n:
        tries += 1
        if tries > 50 * n + 100:
            raise ConfigError(f"World.urban: vehicles = {n} do not fit on the streets of a "
                              f"{size[0]:g} m x {size[1]:g} m city next to its people; allowed: fewer")
        x0, y0, x1, y1 = sts[int(rng.integers(len(sts)))]
        along_x = (x1 - x0) >= (y1 - y0)
        lane = LANES[int(rng.integers(len(LANES)))]
        u = rng.random()
        if along_x:
            x, y, yaw = x0 + 3.0 + u * (x1 - x0 - 6.0), (y0 + y1) / 2 + lane, 0.0 if lane > 0 else math.pi
        else:
            x, y, yaw = (x0 + x1) / 2 + lane, y0 + 3.0 + u * (y1 - y0 - 6.0), math.pi / 2 if lane < 0 else -math.pi / 2
        hx, hy = (half if along_x else half[::-1])
        if not (x0 <= x <= x1 and y0 <= y <= y1):       # a street clipped by the area's edge
            continue
        if math.hypot(x, y) < clear_radius + CAR_LENGTH / 2:
            continue
        if len(people) and ((np.abs(people[:, 0] - x) < hx) & (np.abs(people[:, 1] - y) < hy)).any():
            continue
        if any(abs(x - cx) < hx + ox and abs(y - cy) < hy + oy for cx, cy, ox, oy in out_ext(out)):
            continue
        if inside_buildings(np.array([[x, y]]), bld, margin=CAR_LENGTH / 2).any():
            continue
        out.append((x, y, 0.0, yaw))
    return np.array(out, dtype=float).reshape(-1, 4)


def out_ext(cars):
    """(x, y, half extent x, half extent y) of placed cars."""
    for x, y, _, yaw in cars:
        along_x = abs(math.cos(yaw)) > 0.5
        hx, hy = (CAR_LENGTH / 2, CAR_WIDTH / 2) if along_x else (CAR_WIDTH / 2, CAR_LENGTH / 2)
        yield x, y, hx, hy


#: car colours: white, black, silver, grey, blue, red (the commonest car colours)
CAR_COLOURS = np.array([(0.93, 0.93, 0.92), (0.08, 0.08, 0.09), (0.70, 0.71, 0.73),
                        (0.40, 0.41, 0.43), (0.12, 0.22, 0.55), (0.70, 0.08, 0.08)])
GLASS = (0.12, 0.16, 0.20)
TYRE = (0.06, 0.06, 0.06)


def car_colours(seed: int, n: int) -> np.ndarray:
    return _rng(seed, _S_VEHICLES, 1).integers(0, len(CAR_COLOURS), n)
