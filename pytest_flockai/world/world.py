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

import os
from numbers import Integral, Real

import mujoco
import numpy as np

from .. import _check, limits
from ..errors import ConfigError
from . import urban as _urban
from .mjcf import box_occluders, find_people
from .objects import CAR_BODY, CAR_CABIN, HEAD, PERSON_HEIGHT, TORSO, ObjectTable, _rotate

GROUND_RGBA = (0.45, 0.5, 0.4, 1)

_G_GROUND, _G_BUILDINGS, _G_PEOPLE = 0, 1, 2


class World:
    """A scene: ground, obstacles and people. Build with ``empty``, ``urban`` or ``from_mjcf``."""

    def __init__(self, name: str = "empty"):
        self.name = name
        self.people = np.zeros((0, 3))
        self.truth_height = 0.5 * PERSON_HEIGHT
        self.occluders = np.zeros((0, 6))
        self.buildings = np.zeros((0, 5))     # rows (cx, cy, hx, hy, height)
        self.streets: list = []
        self.size = None
        self.seed = None
        self.crowds: list = []
        self.scattered = 0
        self.vehicles = np.zeros((0, 4))     # rows (x, y, z, yaw): cars
        self.car_idx = np.zeros(0, dtype=int)       # index into urban.CAR_COLOURS per car
        self.clothes_idx = np.zeros(0, dtype=int)   # index into urban.CLOTHES per person
        self.skin_idx = np.zeros(0, dtype=int)      # index into urban.SKIN per person
        self.path = None
        self._info: dict = {}

    # -- constructors ------------------------------------------------------
    @classmethod
    def empty(cls) -> "World":
        return cls("empty")

    @classmethod
    def urban(cls, seed: int = 0, size=(200.0, 200.0), people: int = 100, crowds=(), *,
              building_density: float = 0.7, clear_radius: float = 15.0,
              max_building_height: float | None = None, vehicles: int = 0) -> "World":
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
        w.seed, w.size, w.crowds, w.scattered = int(seed), size, cr, people
        w.buildings = _urban.buildings(int(seed), size, density=density, clear_radius=clear,
                                       keep_clear=keep, max_height=hmax)
        w.streets = _urban.streets(size)
        w.people = _urban.people(int(seed), size, people, cr, w.buildings)
        w.clothes_idx, w.skin_idx = _urban.colours(int(seed), len(w.people))
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
    def scene(cls, people=(), vehicles=(), buildings=(), *, size=(100.0, 100.0)) -> "World":
        """A test range: figures, cars and buildings exactly where you put them, on
        the urban world's ground and streets. people: (x, y) feet positions;
        vehicles: (x, y, yaw) rows; buildings: (cx, cy, half_x, half_y, height)."""
        where = "World.scene"
        size = _check.vector("size", size, 2, where=where, positive_entries=True)
        _check_size(size, where)
        w = cls("urban")
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
        b = w.buildings
        w.occluders = np.column_stack([b[:, 0] - b[:, 2], b[:, 1] - b[:, 3], np.zeros(len(b)),
                                       b[:, 0] + b[:, 2], b[:, 1] + b[:, 3], b[:, 4]])
        w._info = {"scene": True, "vehicles": int(len(cars))}
        return w

    @classmethod
    def from_mjcf(cls, path, people=None) -> "World":
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
    def add_to_spec(self, spec: "mujoco.MjSpec") -> None:
        if self.path is not None:
            self._add_mjcf(spec)
            return
        if self.name != "urban":
            spec.worldbody.add_geom(name="ground", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 1],
                                    rgba=list(GROUND_RGBA))
            return
        self._add_urban(spec)

    def _add_urban(self, spec) -> None:
        G = mujoco.mjtGeom
        wb = spec.worldbody
        spec.add_texture(name="flockai_ground", type=mujoco.mjtTexture.mjTEXTURE_2D,
                         builtin=mujoco.mjtBuiltin.mjBUILTIN_CHECKER, rgb1=[0.36, 0.42, 0.30],
                         rgb2=[0.40, 0.46, 0.33], width=256, height=256,
                         mark=mujoco.mjtMark.mjMARK_EDGE, markrgb=[0.30, 0.34, 0.26])
        ground = spec.add_material(name="flockai_ground", texrepeat=[0.2, 0.2], texuniform=True,
                                   specular=0.0, shininess=0.0, reflectance=0.0)
        ground.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = "flockai_ground"
        spec.add_material(name="flockai_matte", specular=0.0, shininess=0.0, reflectance=0.0)
        spec.add_material(name="flockai_building", specular=0.1, shininess=0.1, reflectance=0.0)
        spec.add_texture(name="flockai_sky", type=mujoco.mjtTexture.mjTEXTURE_SKYBOX,
                         builtin=mujoco.mjtBuiltin.mjBUILTIN_GRADIENT, rgb1=[0.55, 0.75, 0.95],
                         rgb2=[0.95, 0.97, 1.0], width=64, height=384)
        # lighting: sun + a weak headlight; a top face gets ~1.0 (no saturation of colours)
        spec.visual.headlight.ambient = [0.0, 0.0, 0.0]
        spec.visual.headlight.diffuse = [0.2, 0.2, 0.2]
        spec.visual.headlight.specular = [0.0, 0.0, 0.0]
        wb.add_light(name="sun", type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL, pos=[0, 0, 100],
                     dir=[0.3, 0.2, -1.0], diffuse=[0.5, 0.5, 0.5], ambient=[0.3, 0.3, 0.3],
                     specular=[0.0, 0.0, 0.0], castshadow=False)
        wb.add_geom(name="ground", type=G.mjGEOM_PLANE, size=[0, 0, 1], material="flockai_ground",
                    group=_G_GROUND)
        for i, (x0, y0, x1, y1) in enumerate(self.streets):
            wb.add_geom(name=f"street{i}", type=G.mjGEOM_BOX,
                        pos=[(x0 + x1) / 2, (y0 + y1) / 2, 0.02],
                        size=[(x1 - x0) / 2, (y1 - y0) / 2, 0.02], rgba=[0.22, 0.22, 0.24, 1],
                        material="flockai_matte", contype=0, conaffinity=0, group=_G_GROUND)
        shade = np.random.default_rng(np.random.SeedSequence(self.seed, spawn_key=(9,)))
        for i, (cx, cy, hx, hy, h) in enumerate(self.buildings):
            g = 0.55 + 0.3 * shade.random()
            tint = shade.uniform(-0.05, 0.05, 3)
            wb.add_geom(name=f"building{i}", type=G.mjGEOM_BOX, pos=[cx, cy, h / 2],
                        size=[hx, hy, h / 2], rgba=[*np.clip(g + tint, 0, 1), 1],
                        material="flockai_building", group=_G_BUILDINGS)
        self._add_figures(spec)
        self._add_vehicles(spec)

    def _add_figures(self, spec) -> None:
        """People: one mesh geom per colour holding all figures of that colour (group 2)."""
        if len(self.people) == 0:
            return
        for kind, template, idx, palette in (("clothes", TORSO, self.clothes_idx, _urban.CLOTHES),
                                             ("skin", HEAD, self.skin_idx, _urban.SKIN)):
            for c in np.unique(idx):
                verts, faces = _urban.merged(template, self.people[idx == c])
                name = f"people_{kind}{int(c)}"
                spec.add_mesh(name=name, uservert=verts.reshape(-1).tolist(),
                              userface=faces.reshape(-1).tolist())
                spec.worldbody.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=name,
                                        rgba=[*palette[c], 1], material="flockai_matte",
                                        contype=0, conaffinity=0, group=_G_PEOPLE)

    def _add_vehicles(self, spec) -> None:
        """Cars: one mesh per paint colour for the bodies, one for all glasshouses."""
        if len(self.vehicles) == 0:
            return
        parts = [(f"cars_body{int(c)}", CAR_BODY, self.car_idx == c, _urban.CAR_COLOURS[c])
                 for c in np.unique(self.car_idx)]
        parts.append(("cars_glass", CAR_CABIN, np.ones(len(self.vehicles), bool), _urban.GLASS))
        for name, (v, f), mask, rgba in parts:
            cars = self.vehicles[mask]
            verts = np.vstack([_rotate(v, yaw) + (x, y, z) for x, y, z, yaw in cars])
            faces = np.vstack([f + k * len(v) for k in range(len(cars))])
            spec.add_mesh(name=name, uservert=verts.reshape(-1).tolist(),
                          userface=faces.reshape(-1).tolist())
            spec.worldbody.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=name,
                                    rgba=[*rgba, 1], material="flockai_building",
                                    contype=0, conaffinity=0, group=_G_PEOPLE)

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
            self._objects = ObjectTable.build(feet, self.vehicles)
            self._objects_key = key
        return self._objects

    def truth_points(self) -> np.ndarray:
        """(N, 3) points the camera truth projects: people lifted by ``truth_height``."""
        pts = np.array(self.people, dtype=float).reshape(-1, 3)
        pts[:, 2] += self.truth_height
        return pts

    def to_dict(self) -> dict:
        d = {"name": self.name, "people": int(len(self.people))}
        if len(self.vehicles):
            d["vehicles"] = int(len(self.vehicles))
        if self.name == "urban" and self.path is None:
            d.update(seed=self.seed, size=list(self.size), scattered=self.scattered,
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
            count = int(count)
        count = _count(f"{f}.count", count, where)
        spread = _check.positive(f"{f}.spread_m", spread, where=where)
        cap = _urban.crowd_capacity(spread)
        if count > cap:
            raise ConfigError(f"{where}: {f}.count = {count} does not fit a crowd of spread "
                              f"{spread:g} m; allowed: <= {cap} (one person per "
                              f"{_urban.PERSON_AREA_M2:g} m^2 within 2 spreads of the centre)")
        out.append((x, y, count, spread))
    return out
