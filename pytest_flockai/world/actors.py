"""Moving people and cars: actors that walk or drive along paths, on the simulated clock.

An actor follows a polyline ``path`` [(x, y), ...] at a constant ``speed`` from
``start_s`` on (before it stands at the first point, after the last point it
stays there; ``loop=True`` walks the path back and forth for ever). Its position
is a pure function of time, so a flight is deterministic; ``walkers`` draws
random paths from a seed. Every frame, the camera's per-object truth holds each
actor where it is (object ids after the world's own objects), and a rendered
frame shows it there (``ActorSet.place`` moves its mesh geoms just before the
render; physics never sees actors: they do not collide).

Speeds (defaults): people walk at 1.4 m/s, the comfortable gait speed of adults
(Bohannon 1997, "Comfortable and maximum walking speed of adults aged 20-79
years", Age and Ageing 26(1): 127-146 cm/s across age groups; Mohler et al.
2007, Exp. Brain Res. 181: preferred walking speed 1.4 m/s); cars drive at
13.9 m/s (50 km/h, the usual urban speed limit, e.g. German StVO section 3(3)).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from .. import _check, limits
from ..errors import ConfigError
from . import aruco as _aruco
from . import figures as _fig
from .objects import CAR_HEIGHT, CAR_VERTS, PERSON_HEIGHT, ObjectTable, _rotate

WALK_SPEED = 1.4        # m/s, Bohannon 1997 / Mohler et al. 2007 (module docstring)
CAR_SPEED = 13.9        # m/s, 50 km/h urban limit
#: the walking figure's pose row (figures.draw_poses): yaw 0, stature 1, legs and arms swinging
WALK_POSE = (0.0, 1.0, 0.3, -0.3, 0.08, 0.3, 0.08)
_COLOURS = {"top": (0.85, 0.15, 0.1), "legs": (0.15, 0.2, 0.4), "skin": (0.85, 0.65, 0.5),
            "paint": (0.1, 0.3, 0.8), "glass": (0.2, 0.25, 0.3), "tyres": (0.05, 0.05, 0.05)}


class Actor:
    """Base of people and cars: a path, a speed, a start time (see the module docstring)."""

    kind = "person"
    default_speed = WALK_SPEED

    def __init__(self, path, speed: float | None = None, *, start_s: float = 0.0,
                 loop: bool = False, name: str | None = None):
        who = type(self).__name__
        try:
            pts = [tuple(p) for p in path]
        except TypeError:
            raise ConfigError(f"{who}: path = {path!r} is not a list of (x, y) points") from None
        if not pts:
            raise ConfigError(f"{who}: path = [] is empty; give at least one (x, y) point")
        limits.check_at_most("len(path)", len(pts), "MAX_WAYPOINTS", where=who)
        self.path = [_check.vector(f"path[{i}]", p, 2, where=who) for i, p in enumerate(pts)]
        self.speed = _check.positive("speed", self.default_speed if speed is None else speed,
                                     where=who)
        self.start_s = _check.non_negative("start_s", start_s, where=who)
        if not isinstance(loop, bool):
            raise ConfigError(f"{who}: loop = {loop!r} is not allowed; expected True or False")
        self.loop = loop
        if name is not None and (not isinstance(name, str) or not name):
            raise ConfigError(f"{who}: name = {name!r} is not allowed; expected a non-empty str")
        self.name = name
        xy = np.asarray(self.path, dtype=float)
        seg = np.linalg.norm(np.diff(xy, axis=0), axis=1) if len(xy) > 1 else np.zeros(0)
        self._xy, self._cum = xy, np.r_[0.0, np.cumsum(seg)]
        self.length = float(self._cum[-1])

    def at(self, t: float) -> tuple[float, float, float]:
        """(x, y, heading rad) at simulated time t."""
        s = max(0.0, t - self.start_s) * self.speed
        L = self.length
        if L <= 0.0:
            return float(self._xy[0, 0]), float(self._xy[0, 1]), 0.0
        back = False
        if self.loop:
            s = s % (2.0 * L)
            back = s > L
            if back:
                s = 2.0 * L - s
        s = min(s, L)
        i = min(int(np.searchsorted(self._cum, s, side="right")) - 1, len(self._cum) - 2)
        a, b = self._xy[i], self._xy[i + 1]
        f = (s - self._cum[i]) / max(self._cum[i + 1] - self._cum[i], 1e-12)
        d = (b - a) * (-1.0 if back else 1.0)
        return float(a[0] + f * (b[0] - a[0])), float(a[1] + f * (b[1] - a[1])), math.atan2(d[1], d[0])

    def check_inside(self, half_x: float, half_y: float, where: str) -> None:
        """ConfigError naming the first path point outside |x| <= half_x, |y| <= half_y."""
        for i, (x, y) in enumerate(self.path):
            if abs(x) > half_x or abs(y) > half_y:
                raise ConfigError(f"{where}: {self!r} path[{i}] = ({x:g}, {y:g}) is outside the "
                                  f"world; allowed: |x| <= {half_x:g} m, |y| <= {half_y:g} m")

    def to_dict(self) -> dict:
        """JSON-ready description for the flight's scenario."""
        return {"type": type(self).__name__, "name": self.name, "path": [list(p) for p in self.path],
                "speed": self.speed, "start_s": self.start_s, "loop": self.loop}

    def __repr__(self):
        label = f"{self.name!r}, " if self.name else ""
        return f"{type(self).__name__}({label}{len(self.path)} points, speed={self.speed:g})"


class Person(Actor):
    """A person walking ``path`` at ``speed`` (default 1.4 m/s, cited above)."""

    kind = "person"
    default_speed = WALK_SPEED


class Car(Actor):
    """A car driving ``path`` at ``speed`` (default 13.9 m/s = 50 km/h)."""

    kind = "vehicle"
    default_speed = CAR_SPEED


class Marker(Actor):
    """An ArUco marker lying still at (x, y) (``world.aruco``): ``size_m`` the side of
    its black square, ``marker_id`` in ``dictionary``, turned by ``yaw_deg``. It is drawn
    in rendered frames and is no object of the detection truth."""

    kind = "marker"

    def __init__(self, x: float, y: float, *, size_m: float = 1.5, marker_id: int = 0,
                 dictionary: str = "DICT_4X4_50", yaw_deg: float = 0.0, name: str | None = None):
        super().__init__([(x, y)], 1.0, name=name or f"marker{marker_id}")
        where = f"Marker {self.name!r}"
        self.size_m = _check.positive("size_m", size_m, where=where)
        self.dictionary = _check.choice("dictionary", dictionary, _aruco.DICTIONARIES, where=where)
        if isinstance(marker_id, bool) or not isinstance(marker_id, (int, np.integer)) or \
                not 0 <= marker_id < 50:
            raise ConfigError(f"{where}: marker_id = {marker_id!r} is not allowed; expected an "
                              f"int in 0..49")
        self.marker_id = int(marker_id)
        self.yaw_deg = _check.number("yaw_deg", yaw_deg, where=where)

    @property
    def centre(self) -> tuple[float, float]:
        """(x, y) of the marker."""
        x, y = self.path[0]
        return x, y

    def to_dict(self) -> dict:
        """JSON-ready description for the flight's scenario."""
        return {"type": "Marker", "name": self.name, "x": self.centre[0], "y": self.centre[1],
                "size_m": self.size_m, "marker_id": self.marker_id, "dictionary": self.dictionary,
                "yaw_deg": self.yaw_deg}

    def __repr__(self):
        return f"Marker({self.name!r}, at={self.centre}, size_m={self.size_m:g})"


def walk_and_turn(start=(0.0, 0.0), heading_deg: float = 0.0, first_m: float = 60.0,
                  turn_deg: float = 90.0, then_m: float = 60.0, **kw) -> Person:
    """A scripted target: walks ``first_m`` metres along ``heading_deg`` (0 = east,
    counter-clockwise), turns by ``turn_deg`` and walks ``then_m`` more."""
    h1 = math.radians(_check.number("heading_deg", heading_deg, where="walk_and_turn"))
    h2 = h1 + math.radians(_check.number("turn_deg", turn_deg, where="walk_and_turn"))
    x0, y0 = _check.vector("start", start, 2, where="walk_and_turn")
    a = _check.non_negative("first_m", first_m, where="walk_and_turn")
    b = _check.non_negative("then_m", then_m, where="walk_and_turn")
    p1 = (x0 + a * math.cos(h1), y0 + a * math.sin(h1))
    return Person([(x0, y0), p1, (p1[0] + b * math.cos(h2), p1[1] + b * math.sin(h2))], **kw)


def walkers(n: int, area, seed: int = 0, *, legs: int = 4, speed: float = WALK_SPEED) -> list:
    """``n`` people walking random ``legs``-leg paths inside ``area`` ((x0, y0), (x1, y1)),
    drawn from ``seed`` (same seed, same walks); speeds vary +-10 % around ``speed``."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 0:
        raise ConfigError(f"walkers: n = {n!r} is not allowed; expected an int >= 0")
    limits.check_at_most("n", int(n), "MAX_ACTORS", where="walkers")
    x0, y0, x1, y1 = _check.area(area, where="walkers")
    rng = np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(25,)))
    out = []
    for k in range(int(n)):
        pts = np.column_stack([rng.uniform(x0, x1, legs + 1), rng.uniform(y0, y1, legs + 1)])
        v = speed * rng.uniform(0.9, 1.1)
        out.append(Person([tuple(map(float, p)) for p in pts], v, name=f"walker{k}"))
    return out


def traffic(world, n: int, seed: int = 0, *, speed: float = CAR_SPEED) -> list:
    """``n`` cars driving ``world``'s streets (an urban or scene world), each along one
    street's right-hand lane from one end to the other and back (``loop=True``), the
    street and the direction drawn from ``seed``; speeds vary +-10 % around ``speed``."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 0:
        raise ConfigError(f"traffic: n = {n!r} is not allowed; expected an int >= 0")
    limits.check_at_most("n", int(n), "MAX_ACTORS", where="traffic")
    streets = list(getattr(world, "streets", []) or [])
    if n and not streets:
        raise ConfigError(f"traffic: world {getattr(world, 'name', world)!r} has no streets; "
                          f"use World.urban(...) or World.scene(...)")
    rng = np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(26,)))
    out = []
    for k in range(int(n)):
        x0, y0, x1, y1 = streets[int(rng.integers(len(streets)))]
        along_x = (x1 - x0) >= (y1 - y0)
        sign = 1.0 if rng.random() < 0.5 else -1.0
        lane = 0.25 * ((y1 - y0) if along_x else (x1 - x0)) * -sign    # keep right
        cx, cy = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
        ends = ([(x0 + 3.0, cy + lane), (x1 - 3.0, cy + lane)] if along_x
                else [(cx - lane, y0 + 3.0), (cx - lane, y1 - 3.0)])
        if sign < 0:
            ends.reverse()
        out.append(Car(ends, speed * rng.uniform(0.9, 1.1), loop=True, name=f"car{k}"))
    return out


def check_actors(actors, world, where: str = "Mission") -> tuple:
    """The actors as a tuple, each checked to stay inside ``world`` (its size, or
    ``limits.MAX_EXTENT_M`` for unbounded worlds); at most ``limits.MAX_ACTORS``, each
    object listed once (one actor listed twice would be two objects on one path)."""
    try:
        actors = tuple(actors or ())
    except TypeError:
        raise ConfigError(f"{where}: actors = {actors!r} is not a list of fa.actors.Person / Car") from None
    limits.check_at_most("len(actors)", len(actors), "MAX_ACTORS", where=where)
    first: dict[int, int] = {}
    for i, a in enumerate(actors):
        j = first.setdefault(id(a), i)
        if j != i:
            raise ConfigError(f"{where}: actors[{i}] = {a!r} is the same object as actors[{j}]; "
                              f"list each actor once (two people on one path: two Person(...) "
                              f"objects)")
    size = getattr(world, "size", None) if world is not None else None
    hx, hy = ((size[0] / 2, size[1] / 2) if size is not None
              else (limits.MAX_EXTENT_M, limits.MAX_EXTENT_M))
    for i, a in enumerate(actors):
        if not isinstance(a, Actor):
            raise ConfigError(f"{where}: actors[{i}] = {a!r} is not an actor; use "
                              f"fa.actors.Person(path) or fa.actors.Car(path)")
        a.check_inside(hx, hy, f"{where}: actors[{i}]")
    seen: dict = {}
    for i, a in enumerate(actors):         # a name picks one actor (Follow(score=...))
        if a.name and a.name in seen:
            raise ConfigError(f"{where}: actors[{i}].name = {a.name!r} is not allowed: "
                              f"actors[{seen[a.name]}] has that name; names must be unique")
        seen.setdefault(a.name, i)
    return actors


def _meshes(kind: str) -> dict:
    """(vertices, faces) by material of one actor at heading 0, feet at the origin."""
    if kind == "person":
        return _fig.person(WALK_POSE)
    return dict(_fig.CAR)


class ActorSet:
    """The actors of one flight: their truth table at any time, their geoms in the model."""

    def __init__(self, actors):
        everything = tuple(actors)
        #: what moves (people and cars); markers lie still and are drawn only
        self.actors = tuple(a for a in everything if a.kind != "marker")
        self.markers = tuple(a for a in everything if a.kind == "marker")
        self.n_people = sum(a.kind == "person" for a in self.actors)
        self._shape = {k: _meshes(k) for k in ("person", "vehicle")}
        pv = np.vstack([m[0] for m in self._shape["person"].values()])
        self._pshape = (pv, _fig.person_samples(WALK_POSE))
        self._turn_cache: dict = {}
        self._geoms: list = []          # per actor: [(geom id, local pos (3,), local mat (3, 3))]

    def __len__(self) -> int:
        return len(self.actors) + len(self.markers)

    def states(self, t: float) -> list:
        """[(x, y, heading)] of every actor at t."""
        return [a.at(t) for a in self.actors]

    def positions(self, t: float) -> np.ndarray:
        """(N, 3) feet positions of every actor at t (z = 0, the ground)."""
        return np.array([(x, y, 0.0) for x, y, _ in self.states(t)]).reshape(-1, 3)

    def table(self, t: float) -> tuple[np.ndarray, ObjectTable]:
        """(people centres (P, 3), ObjectTable of every actor) at t: people first, then cars."""
        st = self.states(t)
        people = [(s, a) for s, a in zip(st, self.actors) if a.kind == "person"]
        cars = [(s, a) for s, a in zip(st, self.actors) if a.kind != "person"]
        feet = np.array([(x, y, 0.0) for (x, y, _), _ in people]).reshape(-1, 3)
        shapes = [self._turned(h) for (_, _, h), _ in people]
        veh = np.array([(x, y, 0.0, h) for (x, y, h), _ in cars]).reshape(-1, 4)
        tab = ObjectTable.build(feet, veh, shapes=shapes if people else [])
        return feet + (0.0, 0.0, PERSON_HEIGHT / 2), tab

    def _turned(self, heading: float):
        """(vertices, samples) of the walking figure facing ``heading`` (cached: walkers
        keep a heading for a whole leg)."""
        got = self._turn_cache.get(heading)
        if got is None:
            if len(self._turn_cache) > 64:
                self._turn_cache.clear()
            got = (_rotate(self._pshape[0], heading), _rotate(self._pshape[1], heading))
            self._turn_cache[heading] = got
        return got

    # -- rendering ---------------------------------------------------------
    def add_to_spec(self, spec) -> None:
        """One mesh geom per actor and material in the world body (no collisions), and
        each marker's textured slab."""
        for i, m in enumerate(self.markers):
            _aruco.add_marker(spec, f"marker{i}", m.centre, m.size_m, m.dictionary, m.marker_id,
                                m.yaw_deg)
        for i, a in enumerate(self.actors):
            for part, (v, f) in self._shape[a.kind].items():
                name = f"actor{i}_{part}"
                spec.add_mesh(name=name, uservert=np.asarray(v).reshape(-1).tolist(),
                              userface=np.asarray(f).reshape(-1).tolist())
                spec.worldbody.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=name,
                                        rgba=[*_COLOURS[part], 1], contype=0, conaffinity=0,
                                        group=2)

    def bind(self, model) -> None:
        """Find the actors' geoms in the compiled model (their mesh offsets)."""
        self._geoms = []
        for i, a in enumerate(self.actors):
            rows = []
            for part in self._shape[a.kind]:
                g = model.geom(f"actor{i}_{part}").id
                mat = np.zeros(9)
                mujoco.mju_quat2Mat(mat, model.geom_quat[g])
                rows.append((g, model.geom_pos[g].copy(), mat.reshape(3, 3)))
            self._geoms.append(rows)

    def place(self, data, t: float) -> None:
        """Move the actors' geoms to where they are at t (before a render)."""
        for (x, y, h), rows in zip(self.states(t), self._geoms):
            c, s = math.cos(h), math.sin(h)
            R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
            for g, p0, m0 in rows:
                data.geom_xpos[g] = R @ p0 + (x, y, 0.0)
                data.geom_xmat[g] = (R @ m0).reshape(-1)


def merge_tables(a: ObjectTable | None, b: ObjectTable) -> ObjectTable:
    """One table: ``a``'s objects, then ``b``'s (box owners shifted), padded alike."""
    if a is None or len(a) == 0:
        return b
    if len(b) == 0:
        return a
    nv = max(a.verts.shape[1], b.verts.shape[1])
    ns = max(a.samples.shape[1], b.samples.shape[1])

    def pad(x, n):
        if x.shape[1] == n:
            return x
        return np.concatenate([x, np.repeat(x[:, :1], n - x.shape[1], axis=1)], axis=1)

    def padw(w, n):
        return np.concatenate([w, np.zeros((len(w), n - w.shape[1]))], axis=1) if w.shape[1] < n else w
    return ObjectTable(np.r_[a.cls, b.cls], np.vstack([a.centre, b.centre]),
                       np.concatenate([pad(a.verts, nv), pad(b.verts, nv)]),
                       np.concatenate([pad(a.samples, ns), pad(b.samples, ns)]),
                       np.concatenate([padw(a.sample_w, ns), padw(b.sample_w, ns)]),
                       np.vstack([a.boxes, b.boxes]), np.r_[a.box_owner, b.box_owner + len(a)])


__all__ = ["CAR_HEIGHT", "CAR_SPEED", "CAR_VERTS", "WALK_SPEED", "Actor", "ActorSet", "Car",
           "Marker", "Person", "check_actors", "merge_tables", "traffic", "walk_and_turn", "walkers"]
