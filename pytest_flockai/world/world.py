"""Worlds: the scene the drone flies in.

- ``World.empty()``: an unbounded flat ground.
- ``World.urban(seed, size, people, crowds)``: a procedural city (layout in
  ``urban.py``): textured ground, a street grid, box buildings (physics
  obstacles: the drone collides with them), people as simple figures (an
  octagonal torso and a low-poly head, 1.7 m tall; clothing from a 12-colour
  palette) scattered and in Gaussian crowds.
- ``World.from_mjcf(path, people=None)``: a user's static MJCF scene; people
  are its bodies or geoms named ``person*`` (or the positions given).

A world adds itself to the mission's ``mujoco.MjSpec`` with ``add_to_spec``;
everything is a static geom of the world body, so the drone stays body 1 and
the only joint in the model is the drone's free joint.

Geom groups: 0 ground and streets, 1 buildings, 2 people. The figures of
all people wearing the same colour are one mesh geom (``people_clothes<k>``,
``people_skin<k>``): MuJoCo computes the pose of every geom at every physics
step, and two geoms per person doubled the cost of ``mj_step`` for 150 people
(benchmarks/camera.py); merged, the urban world costs ~+25 %. Collisions: the
ground and buildings collide (contype = conaffinity = 1); streets and people
do not (contype = conaffinity = 0), so a figure never knocks the drone out of
the sky and the collision pass only meets the ground and the buildings.

Ground truth: ``world.people`` (N, 3) are the feet of the figures (z = ground);
``world.truth_points()`` the points the camera truth projects (the centre of
each figure, ``people + (0, 0, truth_height)``); ``world.occluders`` (M, 6)
the axis-aligned boxes that hide people from a camera.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Iterable, Sequence
from numbers import Integral, Real
from typing import SupportsInt, cast

import numpy as np

from .. import _check, limits
from .._mujoco import mujoco
from ..errors import ConfigError
from . import figures as _fig
from . import scenery as _scenery
from . import urban as _urban
from .mjcf import box_occluders, find_people
from .objects import PERSON_HEIGHT, ObjectTable

GROUND_RGBA = (0.45, 0.5, 0.4, 1)
FIGURES = ("articulated", "simple")


class World:
    """A scene: ground, obstacles and people. Build with ``empty``, ``urban`` or ``from_mjcf``."""

    def __init__(self, name: str = "empty") -> None:
        self.name = name
        self.people = np.zeros((0, 3))
        self.truth_height = 0.5 * PERSON_HEIGHT
        self.occluders = np.zeros((0, 6))
        self.buildings = np.zeros((0, 5))     # rows (cx, cy, hx, hy, height)
        self.streets: list = []
        self.size: tuple[float, ...] | None = None    # (width, depth) m of an urban world
        self.seed: int | None = None
        self.crowds: list = []
        self.scattered = 0
        self.vehicles = np.zeros((0, 4))     # rows (x, y, z, yaw): cars
        self.car_idx = np.zeros(0, dtype=int)       # index into urban.CAR_COLOURS per car
        self.clothes_idx = np.zeros(0, dtype=int)   # index into urban.CLOTHES per person
        self.skin_idx = np.zeros(0, dtype=int)      # index into urban.SKIN per person
        self.trousers_idx = np.zeros(0, dtype=int)  # index into urban.TROUSERS per person
        self.poses = np.zeros((0, 7))               # figures.draw_poses rows per person
        self.figures = "articulated"
        self.path: str | None = None                 # the MJCF file of World.from_mjcf
        self._info: dict = {}

    # -- constructors ------------------------------------------------------
    @classmethod
    def empty(cls) -> World:
        """A world with nothing in it but the ground."""
        return cls("empty")

    @classmethod
    def urban(cls, seed: int = 0, size: Sequence[float] = (200.0, 200.0), people: int = 100,
              crowds: Iterable = (), *,
              building_density: float = 0.7, clear_radius: float = 15.0,
              max_building_height: float | None = None, vehicles: int = 0,
              figures: str = "articulated") -> World:
        """A procedural city of ``size = (east-west, north-south)`` metres centred on home.

        people: scattered people (uniform over the area, outside buildings);
        crowds: (x, y, count, spread_m) clusters added on top of them
        (Gaussian, per-axis standard deviation spread_m; at most one person per
        0.5 m^2 of the disc of radius 2 spreads). building_density: the
        probability that a lot holds a building; clear_radius: no building
        within this distance of home (0, 0); max_building_height: cap on the
        tallest building (m; default: the built-in range's top). Buildings are
        obstacles: fly above them or around them. vehicles: cars parked at the
        kerbs and standing in the lanes of the streets (drawn from their own
        random stream: adding cars moves nothing else); like people, they are
        seen by the camera and counted by the truth, and do not collide.
        figures: "articulated" (people with legs, arms and a head in varied poses and
        clothing, see ``figures.py``) or "simple" (the first release's torso prism
        and head, kept for comparisons).
        """
        where = "World.urban"
        if isinstance(seed, bool) or not isinstance(seed, Integral) or seed < 0:
            raise ConfigError(f"{where}: seed = {seed!r} is not allowed; expected an integer >= 0")
        size = _check.vector("size", size, 2, where=where, positive_entries=True)
        if min(size) < 20.0:
            raise ConfigError(f"{where}: size = {size!r} is too small; allowed: both sides >= 20 m")
        _check_size(size, where)
        people = _count("people", people, where)
        n_cars = _count("vehicles", vehicles, where)
        limits.check_at_most("people", people, "MAX_PEOPLE", where=where)
        limits.check_at_most("vehicles", n_cars, "MAX_VEHICLES", where=where)
        density = _check.fraction("building_density", building_density, where=where)
        clear = _check.non_negative("clear_radius", clear_radius, where=where)
        hmax = (None if max_building_height is None
                else _check.positive("max_building_height", max_building_height, where=where))
        cr = _crowds(crowds, size, where)
        limits.check_at_most("people (scattered plus crowds)", people + sum(c[2] for c in cr),
                             "MAX_PEOPLE", where=where)
        keep = [(x, y, 2.0 * s + 2.0) for x, y, _, s in cr]
        w = cls("urban")
        w.figures = _figures(figures, where)
        w.seed, w.size, w.crowds, w.scattered = int(seed), size, cr, people
        w.buildings = _urban.buildings(int(seed), size, density=density, clear_radius=clear,
                                       keep_clear=keep, max_height=hmax)
        w.streets = _urban.streets(size)
        w.people = _urban.people(int(seed), size, people, cr, w.buildings)
        w.clothes_idx, w.skin_idx = _urban.colours(int(seed), len(w.people))
        w.poses, w.trousers_idx = _urban.figure_draws(int(seed), len(w.people))
        if n_cars:
            w.vehicles = _urban.vehicles(int(seed), size, n_cars, w.buildings, w.people, clear)
            w.car_idx = _urban.car_colours(int(seed), n_cars)
        b = w.buildings
        w.occluders = np.column_stack([b[:, 0] - b[:, 2], b[:, 1] - b[:, 3], np.zeros(len(b)),
                                       b[:, 0] + b[:, 2], b[:, 1] + b[:, 3], b[:, 4]])
        w._info = {"building_density": density, "clear_radius": clear, "max_building_height": hmax}
        if n_cars:
            w._info["vehicles"] = n_cars
        return w

    @classmethod
    def scene(cls, people: Iterable = (), vehicles: Iterable = (), buildings: Iterable = (), *,
              size: Sequence[float] = (100.0, 100.0), figures: str = "articulated",
              poses: Iterable | None = None) -> World:
        """A test range: figures, cars and buildings exactly where you put them, on
        the urban world's ground and streets. people: (x, y) feet positions;
        vehicles: (x, y, yaw) rows; buildings: (cx, cy, half_x, half_y, height);
        poses: None (drawn as in an urban world of seed 0) or (N, 7) rows as
        ``figures.draw_poses`` returns them."""
        where = "World.scene"
        size = _check.vector("size", size, 2, where=where, positive_entries=True)
        _check_size(size, where)
        w = cls("urban")
        w.figures = _figures(figures, where)
        w.seed, w.size = 0, size
        w.people = _rows(people, 2, "people", "(x, y)", where)
        limits.check_at_most("len(people)", len(w.people), "MAX_PEOPLE", where=where)
        w.people = np.column_stack([w.people, np.zeros(len(w.people))])
        cars = _rows(vehicles, 3, "vehicles", "(x, y, yaw)", where)
        w.vehicles = np.column_stack([cars[:, :2], np.zeros(len(cars)), cars[:, 2]])
        w.car_idx = np.zeros(len(cars), dtype=int)
        w.buildings = _rows(buildings, 5, "buildings", "(cx, cy, half_x, half_y, height)", where)
        w.scattered = len(w.people)
        w.streets = _urban.streets(size)
        w.clothes_idx, w.skin_idx = _urban.colours(0, len(w.people))
        w.poses, w.trousers_idx = _urban.figure_draws(0, len(w.people))
        if poses is not None:
            w.poses = _rows(poses, 7, "poses", "(yaw, scale, swing, left pitch, left roll, "
                            "right pitch, right roll)", where)
            if len(w.poses) != len(w.people):
                raise ConfigError(f"{where}: poses has {len(w.poses)} rows; expected one per "
                                  f"person ({len(w.people)})")
        b = w.buildings
        w.occluders = np.column_stack([b[:, 0] - b[:, 2], b[:, 1] - b[:, 3], np.zeros(len(b)),
                                       b[:, 0] + b[:, 2], b[:, 1] + b[:, 3], b[:, 4]])
        w._info = {"scene": True, "vehicles": int(len(cars))}
        return w

    @classmethod
    def from_mjcf(cls, path: str | os.PathLike, people: Iterable | None = None) -> World:
        """A user's static MJCF scene (no joints; textures resolve relative to the file).

        people: None to find them in the scene (bodies, else geoms, whose name
        starts with ``person``: one person per body, or per geom name up to its
        first ``_``, e.g. ``person3`` and ``person3_head``); or an (N, 3) list
        of positions. The truth projects these positions as they are.
        """
        where = "World.from_mjcf"
        p = os.fspath(path) if isinstance(path, (str, os.PathLike)) else None
        if p is None:
            raise ConfigError(f"{where}: path = {path!r} is not a file path")
        if not os.path.isfile(p):
            raise ConfigError(f"{where}: path = {p!r}: no such file; expected an MJCF (.xml) scene")
        try:
            spec = mujoco.MjSpec.from_file(p)
            model = spec.compile()
        except Exception as exc:   # mujoco raises ValueError with the parser's message
            raise ConfigError(f"{where}: path = {p!r} is not a valid MJCF scene: "
                              f"{str(exc).strip()}") from None
        if model.njnt > 0:
            raise ConfigError(f"{where}: path = {p!r} has {model.njnt} joint(s); allowed: static "
                              f"scenes only (the drone's free joint must be the model's only joint)")
        w = cls(os.path.splitext(os.path.basename(p))[0])
        w.path = os.path.abspath(p)
        w.truth_height = 0.0
        if people is None:
            w.people = find_people(model)
        else:
            try:
                arr = np.asarray(people, dtype=float).reshape(-1, 3)
            except (TypeError, ValueError):
                raise ConfigError(f"{where}: people = {people!r} is not allowed; expected None "
                                  f"or (N, 3) positions") from None
            if not np.isfinite(arr).all():
                raise ConfigError(f"{where}: people has non-finite positions; expected (N, 3) "
                                  f"finite numbers")
            w.people = arr
        w.occluders = box_occluders(model)
        return w

    # -- MuJoCo ------------------------------------------------------------
    def add_to_spec(self, spec: mujoco.MjSpec) -> None:
        """Add this world's ground, buildings, people and vehicles (or its MJCF scene)
        to the flight's MuJoCo model."""
        if self.path is not None:
            self._add_mjcf(spec)
            return
        if self.name != "urban":
            spec.worldbody.add_geom(name="ground", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 1],
                                    rgba=list(GROUND_RGBA))
            return
        _scenery.add_urban(self, spec)

    def _add_mjcf(self, spec) -> None:
        try:
            child = mujoco.MjSpec.from_file(self.path)
        except Exception as exc:
            raise ConfigError(f"World.from_mjcf: path = {self.path!r} is not a valid MJCF scene: "
                              f"{str(exc).strip()}") from None
        frame = spec.worldbody.add_frame()
        spec.attach(child, frame=frame, prefix="scene/")
        # static bodies of the scene are fused into the world body: the drone stays body 1
        spec.compiler.fusestatic = True

    def fingerprint(self) -> str:
        """A digest of the world's content: every public attribute (arrays by their
        bytes) and, for ``from_mjcf``, the scene file's size and modification time.
        Worlds with the same fingerprint add the same model (``add_to_spec``); it keys
        the compiled models (``airframe.model_cache``)."""
        h = hashlib.sha256(type(self).__qualname__.encode())
        for k, v in sorted(vars(self).items()):
            if k.startswith("_") and k != "_info":      # caches derived from the rest
                continue
            h.update(k.encode())
            if isinstance(v, np.ndarray):
                h.update(f"{v.dtype}{v.shape}".encode())
                h.update(np.ascontiguousarray(v).tobytes())
            else:
                h.update(repr(v).encode())
        if self.path is not None and os.path.isfile(self.path):
            st = os.stat(self.path)
            h.update(f"{st.st_size}:{st.st_mtime_ns}".encode())
        return h.hexdigest()

    @property
    def clothes(self) -> np.ndarray:
        """(N, 3) clothing colour (rgb 0..1) of each person."""
        return _urban.CLOTHES[self.clothes_idx].reshape(-1, 3)

    @property
    def skin(self) -> np.ndarray:
        """(N, 3) skin colour (rgb 0..1) of each person."""
        return _urban.SKIN[self.skin_idx].reshape(-1, 3)

    @property
    def objects(self) -> ObjectTable:
        """The objects the camera truth boxes: people (ids 0..N-1), then vehicles."""
        key = (len(self.people), len(self.vehicles))
        if getattr(self, "_objects_key", None) != key:
            feet = np.array(self.people, dtype=float).reshape(-1, 3)
            if self.path is not None:      # from_mjcf: the positions are figure centres
                feet = feet - (0.0, 0.0, PERSON_HEIGHT / 2)
            shapes = None
            if self.path is None and self.figures == "articulated":
                shapes = [(np.vstack([m[0] for m in parts.values()]), _fig.person_samples(pose))
                          for parts, pose in zip(self.figure_meshes(), self.poses)]
            self._objects = ObjectTable.build(feet, self.vehicles, shapes)
            self._objects_key = key
        return self._objects

    def figure_meshes(self) -> list:
        """Per person, ``figures.person(pose)``: its meshes by material (cached)."""
        if getattr(self, "_meshes_n", None) != len(self.poses):
            self._meshes = [_fig.person(p) for p in self.poses]
            self._meshes_n = len(self.poses)
        return self._meshes

    def truth_points(self) -> np.ndarray:
        """(N, 3) points the camera truth projects: people lifted by ``truth_height``."""
        pts = np.array(self.people, dtype=float).reshape(-1, 3)
        pts[:, 2] += self.truth_height
        return pts

    def to_dict(self) -> dict:
        """JSON-ready description for the flight's scenario."""
        d = {"name": self.name, "people": int(len(self.people))}
        if len(self.vehicles):
            d["vehicles"] = int(len(self.vehicles))
        if self.name == "urban" and self.path is None:
            d.update(seed=self.seed, size=None if self.size is None else list(self.size),
                     scattered=self.scattered,
                     figures=self.figures,
                     crowds=[list(c) for c in self.crowds], buildings=int(len(self.buildings)),
                     **self._info)
        if self.path is not None:
            d["path"] = self.path
        return d

    def __repr__(self):
        if self.name == "urban" and self.path is None:
            return (f"World.urban(seed={self.seed}, size={self.size}, people={self.scattered}, "
                    f"crowds={self.crowds})")
        if self.path is not None:
            return f"World.from_mjcf({self.path!r})"
        return f"World({self.name!r})"


def _rows(values, n, field, shape, where) -> np.ndarray:
    try:
        arr = np.asarray(values if len(values) else np.zeros((0, n)), dtype=float).reshape(-1, n)
    except (TypeError, ValueError):
        raise ConfigError(f"{where}: {field} = {values!r} is not allowed; expected rows "
                          f"{shape}") from None
    if arr.shape[0] != len(values) and len(values):
        raise ConfigError(f"{where}: {field} = {values!r} is not allowed; expected rows {shape}")
    if not np.isfinite(arr).all():
        raise ConfigError(f"{where}: {field} has non-finite values; expected rows {shape}")
    return arr


def _figures(value, where) -> str:
    if value not in FIGURES:
        raise ConfigError(f"{where}: figures = {value!r} is not allowed; expected one of "
                          f"{', '.join(map(repr, FIGURES))}")
    return value


def _count(field, value, where) -> int:
    if isinstance(value, bool) or not isinstance(value, Integral) or value < 0:
        raise ConfigError(f"{where}: {field} = {value!r} is not allowed; expected an integer >= 0")
    return int(value)


def _check_size(size, where) -> None:
    for axis, side in zip(("east-west", "north-south"), size):
        limits.check_at_most(f"size = {tuple(size)!r}: {axis} side", side, "MAX_WORLD_SIDE_M",
                             where=where, unit=" m")


def _crowds(crowds, size, where) -> list:
    if crowds is None:
        return []
    try:
        items = list(crowds)
    except TypeError:
        raise ConfigError(f"{where}: crowds = {crowds!r} is not a list; expected "
                          f"[(x, y, count, spread_m), ...]") from None
    out = []
    W, H = size
    for i, c in enumerate(items):
        f = f"crowds[{i}]"
        try:
            x, y, count, spread = c
        except (TypeError, ValueError):
            raise ConfigError(f"{where}: {f} = {c!r} is not allowed; expected "
                              f"(x, y, count, spread_m)") from None
        x = _check.number(f"{f}.x", x, where=where, minimum=-W / 2, maximum=W / 2)
        y = _check.number(f"{f}.y", y, where=where, minimum=-H / 2, maximum=H / 2)
        if isinstance(count, Real) and not isinstance(count, bool) and float(count).is_integer():
            count = int(cast(SupportsInt, count))   # int, float, NumPy: all have __int__
        count = _count(f"{f}.count", count, where)
        spread = _check.positive(f"{f}.spread_m", spread, where=where)
        cap = _urban.crowd_capacity(spread)
        if count > cap:
            raise ConfigError(f"{where}: {f}.count = {count} does not fit a crowd of spread "
                              f"{spread:g} m; allowed: <= {cap} (one person per "
                              f"{_urban.PERSON_AREA_M2:g} m^2 within 2 spreads of the centre)")
        out.append((x, y, count, spread))
    return out
