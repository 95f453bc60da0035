"""The rendered camera: MuJoCo frames of the world from a gimballed camera.

Gimbal. The camera hangs under the drone at ``mount`` (body frame) and a
gimbal keeps it level: its pitch relative to the horizon is ``pitch_deg``
(-90 = straight down) whatever the drone's roll and pitch; it turns with the
drone's yaw (looking down, the top of the image is where the nose points).
At each frame the pose is computed from the body's position, rotation and yaw
(``world.truth.gimbal_pose``) and written into the scene's GL camera after
``mjv_updateScene``: the physics model is not touched, and nothing is
computed between frames. ``add_to_spec`` also adds a MuJoCo camera named
after the sensor to the drone body (body-fixed, at the gimbal's rest pose),
for viewers and for users who want the raw body-fixed view; the rendered
frames do not depend on it.

Rendering. Only the static world is drawn (``mjCAT_STATIC``): the drone's own
hull and propellers never enter the frame. Frames are rendered only when
``read`` is called (the suite never polls a camera: ``on_demand``), into
numpy ``uint8`` arrays of shape (height, width, 3), RGB, row 0 at the top.
The GL context is created on the first frame (``_gl.create_context``: EGL,
then OSMesa); code that never reads a frame never needs OpenGL.

Ground truth. With each frame, ``camera.last_truth`` (a ``Truth``) lists the
people in view and their pixel positions, by pinhole projection of
``world.truth_points()`` (the figure centres) with the same pose and field of
view as the render, less those hidden by buildings (``occlusion=True``, the
world's axis-aligned boxes). ``camera.truth(t, data)`` gives the same without
rendering (cheap: for telemetry).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .. import _check
from .._mujoco import mujoco
from ..errors import ConfigError
from ..world.actors import merge_tables
from ..world.truth import CameraModel, Truth, gimbal_pose
from . import _gl
from .base import DroneBody, Sensor
from .conditions import SKY_SHARE, Conditions, blur_vector, shift_boxes
from .conditions import apply as apply_conditions

NEAR_M = 0.05       # near clipping plane
FAR_M = 5000.0      # far clipping plane
#: m, half the side of the square around the view centre in which the sun casts
#: shadows (MuJoCo's directional shadow map covers +-extent*shadowclip)
SHADOW_HALF_M = 60.0
SHADOW_TEXELS = 2048     # shadow map side: 6 cm per texel over 120 m
SUN_DISTANCE_M = 1000.0  # the shadow camera stands this far up the sun's ray


def _size(field, value, where) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 0 < value <= 8192:
        raise ConfigError(f"{where}: {field} = {value!r} is not allowed; expected an integer "
                          f"number of pixels in 1..8192")
    return int(value)


class FrameRenderer:
    """Offscreen renderer of a model's static scene from an arbitrary camera pose."""

    def __init__(self, model, width: int, height: int):
        self.model, self.width, self.height = model, width, height
        self._ctx = _gl.create_context(width, height)
        self._ctx.make_current()
        vg = model.vis.global_
        vg.offwidth = max(int(vg.offwidth), width)
        vg.offheight = max(int(vg.offheight), height)
        # the shadow map's size and reach are read when the context is made (render only)
        model.vis.quality.shadowsize = SHADOW_TEXELS
        model.vis.map.shadowclip = SHADOW_HALF_M / max(float(model.stat.extent), 1e-6)
        self._con = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_100)
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._con)
        self.scene = mujoco.MjvScene(model, maxgeom=model.ngeom + 64)
        self.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = 0
        self.scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = 0
        self.option = mujoco.MjvOption()
        self._cam = mujoco.MjvCamera()
        self._cam.type = mujoco.mjtCamera.mjCAMERA_FREE
        self._rect = mujoco.MjrRect(0, 0, width, height)
        self._buf = np.empty((height, width, 3), dtype=np.uint8)
        self._depth = np.empty((height, width), dtype=np.float32)
        yy, xx = np.mgrid[0:height, 0:width].astype(np.float32)
        self._ray: tuple[np.ndarray, np.ndarray] | None = None if width == 0 else (xx - width / 2 + 0.5, yy - height / 2 + 0.5)

    def distance(self, fov_deg: float) -> np.ndarray:
        """(H, W) metres from the camera to what each pixel of the last render shows."""
        d = self._depth[::-1]
        z = NEAR_M / (1.0 - d * (1.0 - NEAR_M / FAR_M))            # along the optical axis
        f = 0.5 * self.height / math.tan(math.radians(fov_deg) / 2.0)
        assert self._ray is not None, "a renderer of width 0 renders nothing to measure"
        xx, yy = self._ray
        return z * np.sqrt(1.0 + (xx / f) ** 2 + (yy / f) ** 2)

    def render(self, data, cam_pos, cam_mat, fov_deg: float, *,
               catmask=mujoco.mjtCatBit.mjCAT_STATIC, depth: bool = False,
               sun_dir=None, shadows: bool = False) -> np.ndarray:
        """The frame seen from (cam_pos, cam_mat); ``sun_dir``: the direction the
        sunlight travels (None: the world's own), ``shadows``: the sun casts them."""
        self._ctx.make_current()
        scn = self.scene
        mujoco.mjv_updateScene(self.model, data, self.option, None, self._cam, int(catmask), scn)
        R = np.asarray(cam_mat).reshape(3, 3)
        up, fwd = R[:, 1], -R[:, 2]
        self._light(cam_pos, fwd, sun_dir, shadows)
        half = NEAR_M * math.tan(math.radians(fov_deg) / 2.0)
        for c in scn.camera:           # both eyes at the same place: mono view
            c.pos[:] = cam_pos
            c.forward[:] = fwd
            c.up[:] = up
            c.frustum_center = 0.0
            c.frustum_width = 0.0          # 0: from the viewport's aspect ratio
            c.frustum_bottom = -half
            c.frustum_top = half
            c.frustum_near = NEAR_M
            c.frustum_far = FAR_M
            c.orthographic = 0
        mujoco.mjr_render(self._rect, scn, self._con)
        mujoco.mjr_readPixels(self._buf, self._depth if depth else None, self._rect, self._con)
        return self._buf[::-1].copy()       # OpenGL rows start at the bottom

    def _light(self, cam_pos, fwd, sun_dir, shadows) -> None:
        """Point the world's sun (the shadow-casting directional light) and centre its
        shadow map on the ground point the camera looks at. Given a direction, the
        light becomes physical: the sun's share ``1 / (1 + SKY_SHARE)`` of an
        overhead sun's irradiance times the cosine MuJoCo applies, the sky's share as
        ambient light on the (shadowless) headlight, so a horizontal face receives
        exactly ``Conditions.irradiance`` and a shadow keeps only the sky."""
        scn = self.scene
        scn.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = int(bool(shadows))
        if sun_dir is None and not shadows:
            return
        down = -fwd[2]
        reach = min(cam_pos[2] / down, SHADOW_HALF_M) if down > 1e-3 else 0.0
        target = np.asarray(cam_pos, float) + fwd * reach
        sky = SKY_SHARE / (1.0 + SKY_SHARE)
        for i in range(scn.nlight):
            light = scn.lights[i]
            if sun_dir is not None and light.headlight:
                light.ambient[:] = sky
                light.diffuse[:] = 0.0
            elif light.castshadow and light.type == mujoco.mjtLightType.mjLIGHT_DIRECTIONAL:
                if sun_dir is not None:
                    light.dir[:] = sun_dir
                    light.diffuse[:] = 1.0 - sky
                    light.ambient[:] = 0.0
                d = np.asarray(light.dir, float)
                light.pos[:] = target - d / np.linalg.norm(d) * SUN_DISTANCE_M

    def close(self):
        if self._con is not None:
            self._ctx.make_current()
            self._con.free()
            self._con = None
        if self._ctx is not None:
            self._ctx.free()
            self._ctx = None

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass


class Camera(_check.FrozenSpec, Sensor):
    """A rendered, gimballed camera: ``read(t, data)`` -> RGB frame, ``last_truth``.

    A frozen spec like ``Mission``: its arguments cannot be assigned after construction;
    ``camera.replace(pitch_deg=-45)`` returns a new Camera, checked again.

    width, height (pixels), fov_deg (vertical field of view), pitch_deg
    (gimbal pitch, -90 straight down) as in a blueprint's [camera] section
    (``Camera.from_blueprint(drone)``); rate_hz: frames per second a task may
    ask for (the camera renders whenever ``read`` is called); world: the
    World whose people are the ground truth (``SensorSuite.bind(...,
    world=)`` sets it); occlusion: drop people hidden by buildings from the
    truth. Power 0.9 W: a Raspberry Pi camera module streaming (Xtronix
    measurements: a Pi 3B draws 320 mA headless and 500 mA with the camera
    at 5 V).
    """

    on_demand = True
    SPEC = ("width", "height", "fov_deg", "pitch_deg", "rate_hz", "name", "power_w", "world",
            "occlusion", "mount", "body_name", "objects", "conditions")

    def __init__(self, width: int = 320, height: int = 240, fov_deg: float = 60.0,
                 pitch_deg: float = -90.0, rate_hz: float = 1.0, *, name: str = "camera",
                 power_w: float = 0.9, world=None, occlusion: bool = True,
                 mount=(0.0, 0.0, -0.05), body_name: str = "drone", objects: bool = True,
                 conditions: Conditions | None = None):
        super().__init__(name, rate_hz=rate_hz, power_w=power_w)
        w = f"Camera {name!r}"
        self.width = _size("width", width, w)
        self.height = _size("height", height, w)
        self.fov_deg = _check.number("fov_deg", fov_deg, where=w, minimum=1.0, maximum=170.0)
        self.pitch_deg = _check.number("pitch_deg", pitch_deg, where=w, minimum=-90.0, maximum=90.0)
        self.mount = np.array(_check.vector("mount", mount, 3, where=w))
        self.mount.flags.writeable = False     # part of the frozen spec
        self.body_name = body_name
        self._mounted_on = body_name           # the body add_to_spec put it on (a fleet's prefix)
        self.world = world                     # yours; else each flight's (bind_world)
        self._flight_world = None
        self._actors = None                    # this flight's moving actors (world.actors)
        self.occlusion = bool(occlusion)
        self.objects = bool(objects)          # per-object truth (boxes, visibility) per frame
        if conditions is not None and not isinstance(conditions, Conditions):
            raise ConfigError(f"{w}: conditions = {conditions!r} is not allowed; expected "
                              f"fa.Conditions(...) or None")
        self.conditions = conditions
        self.lens = CameraModel(self.width, self.height, self.fov_deg)
        self.last_frame: np.ndarray | None = None
        self.last_truth: Truth | None = None
        self.last_t: float | None = None
        self.frames = 0
        self._renderer: FrameRenderer | None = None
        self.body: DroneBody | None = None
        self._freeze()

    def _spec_value(self, name: str) -> Any:
        return tuple(self.mount) if name == "mount" else getattr(self, name)

    @classmethod
    def from_blueprint(cls, camera, **kw) -> Camera:
        """From a blueprint's camera section (``drone.camera``) or a Drone having one."""
        sec = getattr(camera, "camera", camera)
        try:
            args: dict[str, Any] = dict(width=int(sec.width), height=int(sec.height), fov_deg=float(sec.fov_deg),
                        pitch_deg=float(sec.pitch_deg))
        except AttributeError:
            raise ConfigError(f"Camera.from_blueprint: {camera!r} has no camera section "
                              f"(width, height, fov_deg, pitch_deg)") from None
        args.update(kw)
        return cls(**args)

    # -- composition ----------------------------------------------------------
    def add_to_spec(self, spec, body_name: str | None = None) -> None:
        """Add a body-fixed MuJoCo camera (the gimbal at rest) and size the framebuffer."""
        body_name = body_name or self.body_name
        self._mounted_on = body_name
        body = spec.body(body_name)
        if body is None:
            raise ConfigError(f"Camera {self.name!r}: body_name = {body_name!r} is not a body "
                              f"of the spec")
        _, R = gimbal_pose((0, 0, 0), 0.0, self.pitch_deg)
        q = np.zeros(4)
        mujoco.mju_mat2Quat(q, R.reshape(-1))
        # a fleet's drone bodies are "<name>/drone": its camera is "<name>/camera"
        prefix = body_name.rpartition("/")[0]
        body.add_camera(name=f"{prefix}/{self.name}" if prefix else self.name,
                        pos=list(self.mount), quat=list(q), fovy=self.fov_deg)
        vg = spec.visual.global_
        vg.offwidth = max(int(vg.offwidth), self.width)
        vg.offheight = max(int(vg.offheight), self.height)

    def bind(self, model, data, rng):
        super().bind(model, data, rng)
        self.body = DroneBody(model, self._mounted_on, f"Camera {self.name!r}")
        world = self.world if self.world is not None else self._flight_world
        if world is not None:
            self._points = world.truth_points()
            self._occ = world.occluders if self.occlusion else None
            self._objects = world.objects if self.objects else None
        else:
            self._points = people_in_model(model, data)
            self._occ = None
            self._objects = None
        if self._renderer is not None and self._renderer.model is not model:
            self._renderer.close()
            self._renderer = None
        self.last_frame = self.last_truth = self.last_t = None
        self.frames = 0

    def bind_world(self, world) -> None:
        """Per flight: the world flown in, used when the camera has no world of its own."""
        self._flight_world = world

    def bind_actors(self, actors) -> None:
        """Per flight: the moving actors (``world.actors.ActorSet``) or None; they join
        the truth of every frame where they are at that time, and the render."""
        self._actors = actors if actors is not None and len(actors) else None

    def _scene(self, t: float):
        """(people points, object table) of the truth at t: the world's, plus the actors."""
        if self._actors is None:
            return self._points, self._objects
        pts, tab = self._actors.table(t)
        objs = merge_tables(self._objects, tab) if self.objects else None
        return np.vstack([self._points, pts]), objs

    # -- pose and truth (no GL) ---------------------------------------------------
    def pose(self, data) -> tuple[np.ndarray, np.ndarray]:
        """(cam_pos, cam_mat) of the gimballed camera in the current state."""
        if self.body is None:
            raise ConfigError(f"Camera {self.name!r}: read before bind(model, data, rng)")
        b = self.body.id
        R = data.xmat[b]
        yaw = math.atan2(R[3], R[0])
        pos = data.xpos[b] + R.reshape(3, 3) @ self.mount
        return gimbal_pose(pos, yaw, self.pitch_deg)

    def truth(self, t: float, data) -> Truth:
        """The ground truth of a frame taken now, without rendering it."""
        cam_pos, cam_mat = self.pose(data)
        points, objects = self._scene(t)
        return self.lens.truth(t, points, cam_pos, cam_mat, self._occ, objects)

    # -- frames ---------------------------------------------------------------
    def read(self, t: float, data) -> np.ndarray:
        if self.body is None:
            raise ConfigError(f"Camera {self.name!r}: read before bind(model, data, rng)")
        cam_pos, cam_mat = self.pose(data)
        if self._actors is not None:
            self._actors.place(data, t)
        frame = self.render_pose(data, cam_pos, cam_mat)
        points, objects = self._scene(t)
        self.last_truth = self.lens.truth(t, points, cam_pos, cam_mat, self._occ, objects)
        if self.conditions is not None:
            b = self.body.id
            w_world = data.xmat[b].reshape(3, 3) @ data.qvel[3:6]     # free joint: body rates
            frame = self._condition(frame, cam_pos, cam_mat, data.qvel[:3], float(w_world[2]))
        self.last_frame, self.last_t = frame, float(t)
        self.frames += 1
        return frame

    def render_pose(self, data, cam_pos, cam_mat) -> np.ndarray:
        """Render the scene from ``cam_pos`` looking along ``cam_mat`` (RGB uint8)."""
        if self._renderer is None:
            self._renderer = FrameRenderer(self.model, self.width, self.height)
        c = self.conditions
        if c is None:
            return self._renderer.render(data, cam_pos, cam_mat, self.fov_deg)
        return self._renderer.render(data, cam_pos, cam_mat, self.fov_deg, depth=c.needs_depth,
                                     sun_dir=c.sun_dir, shadows=c.shadows)

    def _condition(self, frame, cam_pos, cam_mat, velocity, yaw_rate) -> np.ndarray:
        """Light, haze, motion blur, exposure and noise (``sensors.conditions``)."""
        c, renderer, truth = self.conditions, self._renderer, self.last_truth
        assert c is not None and renderer is not None and truth is not None, \
            "read() renders and takes the truth before it conditions a frame"
        dist = renderer.distance(self.fov_deg) if c.needs_depth else None
        centre = ground_distance(cam_pos, cam_mat)    # one rule, haze or not (conditions)
        jitter = math.radians(c.gimbal_jitter_dps)
        blur = blur_vector(cam_pos, cam_mat, velocity, yaw_rate, c.exposure_s, self.lens.focal_px,
                           centre, jitter)
        skew = blur_vector(cam_pos, cam_mat, velocity, yaw_rate, c.readout_s, self.lens.focal_px,
                           centre, jitter)
        record_skew(truth, skew, self.width, self.height)
        truth.blur_px = blur
        return apply_conditions(frame, c, self.rng, distance=dist, blur=blur, skew=skew)

    def close(self) -> None:
        """Free the renderer's GL context (it is rebuilt on the next read)."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def to_dict(self):
        return {**super().to_dict(), "width": self.width, "height": self.height,
                "fov_deg": self.fov_deg, "pitch_deg": self.pitch_deg}

    def __repr__(self):
        return (f"Camera({self.width}x{self.height}, fov_deg={self.fov_deg:g}, "
                f"pitch_deg={self.pitch_deg:g}, rate_hz={self.rate_hz:g})")


def record_skew(truth, skew, width: int, height: int) -> None:
    """Put a rolling shutter's skew into a frame's truth: ``skew_px`` and the object boxes
    (moved with their centre row, clipped to the image)."""
    truth.skew_px = skew
    if truth.objects is not None and len(truth.objects):
        b = shift_boxes(truth.objects.boxes, skew, height)
        truth.objects.boxes = np.clip(b, 0.0, [width, height, width, height])


def ground_distance(cam_pos, cam_mat) -> float:
    """Distance along the optical axis to the ground plane (z = 0), or the height."""
    axis = -np.asarray(cam_mat, dtype=float).reshape(3, 3)[:, 2]
    down = -axis[2]
    return float(cam_pos[2] / down) if down > 1e-3 else float(cam_pos[2])


def people_in_model(model, data) -> np.ndarray:
    """People of a compiled model by name: geoms ``person*`` grouped up to the first ``_``."""
    groups: dict[str, list] = {}
    for g in range(model.ngeom):
        base = (model.geom(g).name or "").rsplit("/", 1)[-1]
        if base.startswith("person"):
            groups.setdefault(base.split("_", 1)[0], []).append(data.geom_xpos[g].copy())
    return np.array([np.mean(v, axis=0) for v in groups.values()]).reshape(-1, 3)
