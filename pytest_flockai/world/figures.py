"""Figures that look the part: articulated people and cars with body, glass and wheels.

Pure numpy geometry (no MuJoCo): each function returns triangle meshes as
``(vertices (V, 3), faces (F, 3))`` with outward faces, in metres, in the
object's frame (x forward, y left, z up, feet or tyres on the ground at z = 0).
``World`` merges them into one mesh geom per material (so ``mj_step`` stays
fast) and ``objects.ObjectTable`` projects the same vertices for the truth
boxes, so a box is the tight box of what is drawn.

**People** (``World.urban(figures="articulated")``, the default): two legs,
a torso, two arms and a head, proportioned after adult anthropometry (stature
1.70 m; hip height 0.84 m, shoulder height 1.40 m, shoulder breadth 0.47 m,
arm length 0.62 m: NASA-STD-3000 Vol. I, Sec. 3 (Anthropometry), 50th
percentile figures rounded), in one of four poses drawn per person with a
facing direction and a stature scale (standard deviation 6 %):

- standing (arms hanging, slightly apart);
- walking (legs and arms swinging in opposite phase, up to 20 degrees);
- waving (one arm raised above the head);
- pointing (one arm held forward).

Clothing: a top (torso and arms) and trousers (legs) from two palettes, skin
for the head. **Cars** keep the Golf 8's outer size (4.3 x 1.8 x 1.46 m):
a painted body, a sloped glasshouse (windscreen, side and rear windows) under
a painted roof, and four tyres.
"""

from __future__ import annotations

import math

import numpy as np

STATURE = 1.70              # m, nominal height of a figure (scaled per person)
HIP_Z, SHOULDER_Z = 0.84, 1.40
HIP_Y, SHOULDER_Y = 0.10, 0.235
LEG_R, ARM_R, ARM_LEN = 0.075, 0.045, 0.62
TORSO_HX, TORSO_HY, TORSO_Z0, TORSO_Z1 = 0.12, 0.19, 0.80, 1.46
HEAD_R, HEAD_Z = 0.11, STATURE - 0.11
STATURE_SD = 0.06           # relative standard deviation of the stature scale
POSES = ("standing", "walking", "waving", "pointing")
POSE_P = (0.3, 0.5, 0.1, 0.1)


def prism(n, r, z0, z1):
    """(vertices, faces) of an n-gon prism of radius r around the z axis, outward faces."""
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
    """(vertices, faces) of an axis-aligned box along x, centred at x = cx."""
    x0, x1 = cx - hx, cx + hx
    v = np.array([[x, y, z] for z in (z0, z1) for y in (-hy, hy) for x in (x0, x1)], dtype=float)
    f = np.array([(0, 2, 3), (0, 3, 1), (4, 5, 7), (4, 7, 6), (0, 1, 5), (0, 5, 4),
                  (2, 6, 7), (2, 7, 3), (0, 4, 6), (0, 6, 2), (1, 3, 7), (1, 7, 5)])
    return v, f


def frustum(bottom, top, z0, z1):
    """(vertices, faces) of a box whose bottom rectangle (x0, x1, hy) at z0 narrows to
    the top rectangle at z1 (a glasshouse: sloped windscreen and rear window)."""
    (bx0, bx1, bhy), (tx0, tx1, thy) = bottom, top
    v = np.array([[bx0, -bhy, z0], [bx1, -bhy, z0], [bx0, bhy, z0], [bx1, bhy, z0],
                  [tx0, -thy, z1], [tx1, -thy, z1], [tx0, thy, z1], [tx1, thy, z1]], dtype=float)
    return v, box(0, 1, 1, 0, 1)[1]


def rot_x(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _limb(mesh, R, at):
    v, f = mesh
    return v @ R.T + at, f


LEG = prism(6, LEG_R, -HIP_Z, 0.0)
ARM = prism(6, ARM_R, -ARM_LEN, 0.0)
TORSO = (prism(8, 1.0, TORSO_Z0, TORSO_Z1)[0] * (TORSO_HX, TORSO_HY, 1.0), prism(8, 1.0, 0, 1)[1])
HEAD = sphere(8, 4, HEAD_R, HEAD_Z)


def draw_poses(rng: np.random.Generator, n: int) -> np.ndarray:
    """(n, 7) pose rows: yaw, stature scale, leg swing, left arm (pitch, roll), right
    arm (pitch, roll); angles in radians, pitch forward, roll outward."""
    kind = rng.choice(len(POSES), size=n, p=POSE_P)
    yaw = rng.uniform(0.0, 2 * math.pi, n)
    scale = np.clip(1.0 + STATURE_SD * rng.standard_normal(n), 0.85, 1.15)
    phase = rng.uniform(-1.0, 1.0, n)
    side = rng.integers(0, 2, n)
    out = np.zeros((n, 7))
    out[:, 0], out[:, 1] = yaw, scale
    out[:, 4] = out[:, 6] = 0.08                                  # arms slightly apart
    walk = kind == 1
    out[walk, 2] = 0.35 * phase[walk]
    out[walk, 3] = -0.35 * phase[walk]
    out[walk, 5] = 0.35 * phase[walk]
    for k, (pitch, roll) in ((2, (0.2, 2.6)), (3, (1.45, 0.1))):   # waving, pointing
        m = kind == k
        col = np.where(side[m] == 0, 3, 5)
        out[np.flatnonzero(m), col] = pitch
        out[np.flatnonzero(m), col + 1] = roll
    return out


def person(pose) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """The meshes of one figure in its pose, by material: ``top``, ``legs``, ``skin``.
    Vertices are relative to the feet, turned by the pose's yaw and scaled."""
    yaw, scale, swing, lp, lr, rp, rr = (float(x) for x in pose)
    parts = {"top": [TORSO], "legs": [], "skin": [HEAD]}
    for sgn, s in ((1, 1.0), (-1, -1.0)):
        parts["legs"].append(_limb(LEG, rot_y(-s * swing), (0.0, sgn * HIP_Y, HIP_Z)))
    parts["top"].append(_limb(ARM, rot_x(lr) @ rot_y(-lp), (0.0, SHOULDER_Y, SHOULDER_Z)))
    parts["top"].append(_limb(ARM, rot_x(-rr) @ rot_y(-rp), (0.0, -SHOULDER_Y, SHOULDER_Z)))
    R = rot_z(yaw) * scale
    return {name: merge((v @ R.T, f) for v, f in meshes) for name, meshes in parts.items()}


def person_samples(pose) -> np.ndarray:
    """17 points through a figure's volume (its visible fraction is the share a
    camera sees): a ring of 8 and two axis points in the torso, two per leg, the
    middle of each arm and the head's centre; relative to the feet."""
    yaw, scale, swing, lp, lr, rp, rr = (float(x) for x in pose)
    a = (np.arange(8) + 0.5) * math.pi / 4
    pts = [(0.7 * TORSO_HX * math.cos(t), 0.7 * TORSO_HY * math.sin(t), 1.1) for t in a]
    pts += [(0.0, 0.0, 0.95), (0.0, 0.0, 1.3), (0.0, 0.0, HEAD_Z)]
    for sgn, s in ((1, 1.0), (-1, -1.0)):
        R = rot_y(-s * swing)
        for f in (0.3, 0.7):
            pts.append(R @ (0.0, 0.0, -f * HIP_Z) + (0.0, sgn * HIP_Y, HIP_Z))
    for y, R in ((SHOULDER_Y, rot_x(lr) @ rot_y(-lp)), (-SHOULDER_Y, rot_x(-rr) @ rot_y(-rp))):
        pts.append(R @ (0.0, 0.0, -0.5 * ARM_LEN) + (0.0, y, SHOULDER_Z))
    return np.asarray(pts) @ (rot_z(yaw) * scale).T


# -- cars ---------------------------------------------------------------------------
CAR_LENGTH, CAR_WIDTH, CAR_HEIGHT = 4.3, 1.8, 1.46     # Golf 8: 4284 x 1789 x 1456 mm
TYRE_R, TYRE_W, WHEELBASE, TRACK = 0.32, 0.22, 2.64, 1.56    # Golf 8: wheelbase 2636 mm
CAR_PAINT = (box(0.0, CAR_LENGTH / 2, CAR_WIDTH / 2, 0.30, 0.95),
             box(-0.30, 0.72, 0.66, 1.40, CAR_HEIGHT))                     # body, roof
CAR_GLASS = (frustum((-1.45, 0.95, 0.80), (-1.05, 0.45, 0.68), 0.95, 1.40),)
CAR_TYRES = tuple(_limb(prism(8, TYRE_R, -TYRE_W / 2, TYRE_W / 2), rot_x(math.pi / 2),
                        (sx * WHEELBASE / 2, sy * (TRACK / 2), TYRE_R * math.cos(math.pi / 8)))
                  for sx in (-1, 1) for sy in (-1, 1))


def merge(meshes):
    """One (vertices, faces) mesh from several."""
    vs, fs, k = [], [], 0
    for v, f in meshes:
        vs.append(np.asarray(v, float))
        fs.append(np.asarray(f) + k)
        k += len(v)
    return np.vstack(vs), np.vstack(fs)


CAR = {"paint": merge(CAR_PAINT), "glass": merge(CAR_GLASS), "tyres": merge(CAR_TYRES)}
