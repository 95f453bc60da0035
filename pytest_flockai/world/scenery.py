"""The urban scene as MjSpec geoms: ground, streets, buildings, the sun, people and cars.

Everything is a static geom of the world body. The figures of all people
wearing the same colour are one mesh geom per material (``people_top<k>``,
``people_legs<k>``, ``people_skin<k>``), and the cars one mesh per paint colour
plus one for all glass and one for all tyres: MuJoCo computes the pose of every
geom at every physics step, and two geoms per person doubled the cost of
``mj_step`` for 150 people (benchmarks/camera.py); merged, the urban world costs
~+25 %. Streets, people and cars do not collide (contype = conaffinity = 0).

The sun is a directional light that casts shadows; the renderer draws them
only when a camera's ``Conditions`` ask for them (``shadows=True``), and points
the sun as the conditions say (``sun_azimuth_deg``, ``sun_elevation_deg``).
"""

from __future__ import annotations

from .._mujoco import mujoco
import numpy as np

from . import figures as _fig
from . import urban as _urban
from .objects import HEAD, SIMPLE_CAR, TORSO, _rotate

G_GROUND, G_BUILDINGS, G_PEOPLE = 0, 1, 2
#: default sun direction (pointing from the sun): azimuth ~214 deg, elevation ~70 deg
SUN_DIR = (0.3, 0.2, -1.0)


def add_urban(world, spec) -> None:
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
    spec.add_material(name="flockai_glass", specular=0.5, shininess=0.8, reflectance=0.0)
    spec.add_texture(name="flockai_sky", type=mujoco.mjtTexture.mjTEXTURE_SKYBOX,
                     builtin=mujoco.mjtBuiltin.mjBUILTIN_GRADIENT, rgb1=[0.55, 0.75, 0.95],
                     rgb2=[0.95, 0.97, 1.0], width=64, height=384)
    # lighting: sun + a weak headlight; a top face gets ~1.0 (no saturation of colours).
    # The ambient (sky) light rides on the headlight, which casts no shadow, so a
    # shadow keeps the sky's share instead of going black.
    spec.visual.headlight.ambient = [0.3, 0.3, 0.3]
    spec.visual.headlight.diffuse = [0.2, 0.2, 0.2]
    spec.visual.headlight.specular = [0.0, 0.0, 0.0]
    spec.visual.quality.shadowsize = 1024       # shadow map texels (read when a renderer is made)
    wb.add_light(name="sun", type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL, pos=[0, 0, 100],
                 dir=list(SUN_DIR), diffuse=[0.5, 0.5, 0.5], ambient=[0.0, 0.0, 0.0],
                 specular=[0.0, 0.0, 0.0], castshadow=True)
    wb.add_geom(name="ground", type=G.mjGEOM_PLANE, size=[0, 0, 1], material="flockai_ground",
                group=G_GROUND)
    for i, (x0, y0, x1, y1) in enumerate(world.streets):
        # streets along y stand 1 mm prouder than those along x: no coplanar overlap at
        # crossings (the light passes would add up there)
        z = 0.021 if (y1 - y0) > (x1 - x0) else 0.02
        wb.add_geom(name=f"street{i}", type=G.mjGEOM_BOX,
                    pos=[(x0 + x1) / 2, (y0 + y1) / 2, z],
                    size=[(x1 - x0) / 2, (y1 - y0) / 2, 0.02], rgba=[0.22, 0.22, 0.24, 1],
                    material="flockai_matte", contype=0, conaffinity=0, group=G_GROUND)
    shade = np.random.default_rng(np.random.SeedSequence(world.seed, spawn_key=(9,)))
    for i, (cx, cy, hx, hy, h) in enumerate(world.buildings):
        g = 0.55 + 0.3 * shade.random()
        tint = shade.uniform(-0.05, 0.05, 3)
        wb.add_geom(name=f"building{i}", type=G.mjGEOM_BOX, pos=[cx, cy, h / 2],
                    size=[hx, hy, h / 2], rgba=[*np.clip(g + tint, 0, 1), 1],
                    material="flockai_building", group=G_BUILDINGS)
    _add_figures(world, spec)
    _add_vehicles(world, spec)


def _mesh_geom(spec, name, verts, faces, rgba, material):
    spec.add_mesh(name=name, uservert=np.asarray(verts).reshape(-1).tolist(),
                  userface=np.asarray(faces).reshape(-1).tolist())
    spec.worldbody.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_MESH, meshname=name,
                            rgba=[*rgba, 1], material=material, contype=0, conaffinity=0,
                            group=G_PEOPLE)


def _add_figures(world, spec) -> None:
    """People: one mesh geom per material and colour holding all figures of that colour."""
    if len(world.people) == 0:
        return
    if world.figures == "simple":
        for kind, template, idx, palette in (("clothes", TORSO, world.clothes_idx, _urban.CLOTHES),
                                             ("skin", HEAD, world.skin_idx, _urban.SKIN)):
            for c in np.unique(idx):
                verts, faces = _urban.merged(template, world.people[idx == c])
                _mesh_geom(spec, f"people_{kind}{int(c)}", verts, faces, palette[c],
                           "flockai_matte")
        return
    meshes = world.figure_meshes()
    for part, idx, palette in (("top", world.clothes_idx, _urban.CLOTHES),
                               ("legs", world.trousers_idx, _urban.TROUSERS),
                               ("skin", world.skin_idx, _urban.SKIN)):
        for c in np.unique(idx):
            sel = np.flatnonzero(idx == c)
            verts, faces = _fig.merge([(meshes[i][part][0] + world.people[i], meshes[i][part][1])
                                       for i in sel])
            _mesh_geom(spec, f"people_{part}{int(c)}", verts, faces, palette[c], "flockai_matte")


def _add_vehicles(world, spec) -> None:
    """Cars: one mesh per paint colour for the bodies, one for all glass, one for all tyres
    (articulated figures; simple figures keep the first release's box cars)."""
    if len(world.vehicles) == 0:
        return
    everyone = np.ones(len(world.vehicles), bool)
    simple = world.figures == "simple"
    paint = SIMPLE_CAR[0] if simple else _fig.CAR["paint"]
    parts = [(f"cars_body{int(c)}", paint, world.car_idx == c,
              _urban.CAR_COLOURS[c], "flockai_building") for c in np.unique(world.car_idx)]
    if simple:       # the first release's cars: a body box and a glass cabin box
        parts.append(("cars_glass", SIMPLE_CAR[1], everyone, _urban.GLASS, "flockai_building"))
    else:
        parts.append(("cars_glass", _fig.CAR["glass"], everyone, _urban.GLASS, "flockai_glass"))
        parts.append(("cars_tyres", _fig.CAR["tyres"], everyone, _urban.TYRE, "flockai_matte"))
    for name, (v, f), mask, rgba, material in parts:
        verts, faces = _fig.merge([(_rotate(v, yaw) + (x, y, z), f)
                                   for x, y, z, yaw in world.vehicles[mask]])
        _mesh_geom(spec, name, verts, faces, rgba, material)
