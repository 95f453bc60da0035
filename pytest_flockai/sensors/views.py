"""Frames of a world from given camera poses, without a drone or a mission.

``render_views(world, poses, camera)`` renders each pose once and returns
``[(frame, truth)]``: training data, or a fixed scene for a test.
``ViewSet(world, poses, camera)`` keeps the renders (and their depth) so that
the same views can be seen under many imaging conditions cheaply:
``views.under(fa.Conditions(...), velocity=(12, 0, 0))`` only re-applies light,
haze, blur, rolling shutter, weather and noise (numpy and OpenCV, no
rendering), which is what a hypothesis search over conditions needs; a sun
direction or shadows (``Conditions.relights``) render the views again under
that sun.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from .. import memo
from .._mujoco import mujoco
from ..errors import ConfigError
from ..world.truth import gimbal_pose
from .camera import Camera, FrameRenderer, ground_distance, record_skew
from .conditions import Conditions, blur_vector
from .conditions import apply as apply_conditions


def _camera_params(camera_params) -> Camera:
    if isinstance(camera_params, Camera):
        return camera_params
    if isinstance(camera_params, dict):
        return Camera(**camera_params)
    if camera_params is None:
        return Camera()
    return Camera.from_blueprint(camera_params)


def _poses(poses) -> list:
    rows = []
    for i, p in enumerate(poses):
        try:
            vals = [float(v) for v in p]
        except (TypeError, ValueError):
            raise ConfigError(f"render_views: poses[{i}] = {p!r} is not allowed; expected "
                              f"(x, y, z) or (x, y, z, yaw)") from None
        if len(vals) not in (3, 4) or not all(math.isfinite(v) for v in vals):
            raise ConfigError(f"render_views: poses[{i}] = {p!r} is not allowed; expected "
                              f"(x, y, z) or (x, y, z, yaw) finite numbers")
        rows.append(vals + [0.0] * (4 - len(vals)))
    return rows


class ViewSet:
    """Renders of ``world`` from ``poses`` ((x, y, z) or (x, y, z, yaw) rows; yaw in
    rad, 0 = the image top points east when looking down), with their truth and
    depth; ``camera``: a Camera, a dict of its arguments, a blueprint camera
    section, or None (320x240, 60 deg, straight down)."""

    def __init__(self, world, poses, camera=None, *, depth: bool = True):
        cam = self.camera = _camera_params(camera)
        rows = _poses(poses)
        self._world = world
        self._model = self._data = None          # compiled on the first render
        points = world.truth_points()
        occ = world.occluders if cam.occlusion else None
        objects = world.objects if cam.objects else None
        self.poses = [gimbal_pose((x, y, z), yaw, cam.pitch_deg) for x, y, z, yaw in rows]
        self.truths = [cam.lens.truth(0.0, points, p, m, occ, objects) for p, m in self.poses]
        self.frames, self.distances = self._render(depth)

    def _render(self, depth: bool, sun_dir=None, shadows: bool = False):
        """(frames, distances); memoised (``pytest_flockai.memo``) on the world, the
        poses, the camera and the light."""
        inputs = {"world": self._world, "poses": self.poses, "camera": self.camera,
                  "depth": depth, "sun_dir": sun_dir, "shadows": shadows}
        out = memo.recall("views", inputs, lambda: self._render_now(depth, sun_dir, shadows),
                          pack=lambda fd: {"frames": fd[0], "distances": fd[1]},
                          unpack=lambda d: (list(d["frames"]), list(d["distances"])))
        return out

    def _compile(self) -> None:
        cam = self.camera
        spec = mujoco.MjSpec()
        spec.modelname = "flockai_views"
        self._world.add_to_spec(spec)
        vg = spec.visual.global_
        vg.offwidth = max(int(vg.offwidth), cam.width)
        vg.offheight = max(int(vg.offheight), cam.height)
        self._model = spec.compile()
        self._data = mujoco.MjData(self._model)
        mujoco.mj_forward(self._model, self._data)

    def _render_now(self, depth: bool, sun_dir, shadows: bool):
        if self._model is None:
            self._compile()
        cam = self.camera
        renderer = FrameRenderer(self._model, cam.width, cam.height)
        frames, distances = [], []
        try:
            for cam_pos, cam_mat in self.poses:
                frames.append(renderer.render(self._data, cam_pos, cam_mat, cam.fov_deg,
                                              depth=depth, sun_dir=sun_dir, shadows=shadows))
                distances.append(renderer.distance(cam.fov_deg).astype(np.float32)
                                 if depth else None)
        finally:
            renderer.close()
        return frames, distances

    def __len__(self) -> int:
        return len(self.frames)

    def ideal(self) -> list:
        """[(frame, truth)] as rendered."""
        return list(zip(self.frames, self.truths))

    def under(self, conditions: Conditions, *, velocity=(0.0, 0.0, 0.0), seed: int = 0) -> list:
        """[(frame, truth)] under ``conditions``, the camera moving at ``velocity``
        (m/s, world frame) during its exposure; ``seed``: the sensor noise."""
        if not isinstance(conditions, Conditions):
            raise ConfigError(f"ViewSet.under: conditions = {conditions!r} is not a fa.Conditions")
        cam, items = self.camera, []
        frames, distances = self.frames, self.distances
        if conditions.needs_depth and any(d is None for d in distances):
            raise ConfigError("ViewSet.under: haze needs depth; build the ViewSet with depth=True")
        if conditions.relights:
            frames, distances = self._render(conditions.needs_depth, conditions.sun_dir,
                                             conditions.shadows)
        for frame, truth, (pos, mat), dist in zip(frames, self.truths, self.poses, distances):
            centre = ground_distance(pos, mat)        # the camera's rule (conditions)
            blur = blur_vector(pos, mat, velocity, 0.0, conditions.exposure_s, cam.lens.focal_px,
                               centre)
            skew = blur_vector(pos, mat, velocity, 0.0, conditions.readout_s, cam.lens.focal_px,
                               centre)
            t = dataclasses.replace(truth, blur_px=blur,
                                    objects=dataclasses.replace(truth.objects))
            record_skew(t, skew, cam.width, cam.height)
            items.append((frame, dist, blur, skew, t))

        def apply():
            rng = np.random.default_rng(seed)
            return [apply_conditions(f, conditions, rng, distance=d, blur=b, skew=s)
                    for f, d, b, s, _ in items]
        inputs = {"world": self._world, "poses": self.poses, "camera": cam,
                  "depth": [d is not None for d in distances], "conditions": conditions,
                  "velocity": velocity, "seed": seed}
        seen = memo.recall("views-under", inputs, apply, pack=lambda fs: {"frames": fs},
                           unpack=lambda d: list(d["frames"]))
        return list(zip(seen, [it[4] for it in items]))


def render_views(world, poses, camera_params=None, *, conditions=None, velocity=(0.0, 0.0, 0.0),
                 seed: int = 0) -> list:
    """Render a World from camera poses, without a drone or a mission: [(frame, truth)].

    Useful to build training data: frames and ground truth from the same
    renderer the missions use. conditions: ``fa.Conditions`` applied to each
    frame as if the camera moved at ``velocity`` (m/s, world frame) during its
    exposure; ``seed``: its noise. To see the same views under many
    conditions, build a ``ViewSet`` once.
    """
    views = ViewSet(world, poses, camera_params,
                    depth=conditions is not None and conditions.needs_depth)
    if conditions is None:
        return views.ideal()
    return views.under(conditions, velocity=velocity, seed=seed)
