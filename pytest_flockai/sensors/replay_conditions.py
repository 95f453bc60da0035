"""Imaging conditions on replayed frames: what is physical without a depth buffer.

A recorded image has no depth and cannot be lit again, so of ``Conditions`` a
``ReplayCamera(conditions=...)`` applies (``sensors.conditions.apply``):

- **motion blur** and the **rolling-shutter skew** of the simulated flight: the
  drone's velocity and yaw rate at the read, a camera looking straight down
  (``fov_deg``: its vertical field of view), the scene point at the ground under
  the image centre (the rendered camera's rule), over ``exposure_s`` / ``readout_s``;
- **light** (``sun_elevation_deg``: the frame is taken as shot under an overhead
  sun and dimmed to the elevation), **exposure** (auto-exposure gain) and **sensor
  noise** (shot and read noise);
- **weather** (rain, snow, spatter): image corruptions that need no depth.

Refused with a ConfigError: **haze** (``visibility_m``: Koschmieder's attenuation
needs each pixel's distance) and the **sun direction and shadows**
(``sun_azimuth_deg``, ``shadows``: a render of the scene under that sun).
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import ConfigError
from ..world.truth import focal_px, gimbal_pose
from .camera import ground_distance
from .conditions import Conditions, blur_vector
from .conditions import apply as apply_conditions


def check(cond, where: str):
    """ConfigError unless ``cond`` is None or Conditions a recorded frame can take."""
    if cond is None:
        return None
    if not isinstance(cond, Conditions):
        raise ConfigError(f"{where}: conditions = {cond!r} is not allowed; expected "
                          f"fa.Conditions(...) or None")
    if cond.needs_depth:
        raise ConfigError(f"{where}: visibility_m = {cond.visibility_m!r}: haze needs each "
                          f"pixel's distance, which a recorded image does not have; allowed on "
                          f"replayed frames: exposure_s, readout_s, sun_elevation_deg, noise, "
                          f"exposure and weather")
    if cond.relights:
        raise ConfigError(f"{where}: sun_azimuth_deg / shadows need a render of the scene "
                          f"under that sun; a recorded image cannot be lit again")
    return cond


def condition(frame, cond: Conditions, rng, data, body_id: int, fov_deg: float, truth):
    """(``frame`` as the sensor records it in the current flight state, blur (du, dv));
    the blur and skew go to ``truth`` (when there is one)."""
    R = data.xmat[body_id]
    yaw = math.atan2(R[3], R[0])
    cam_pos, cam_mat = gimbal_pose(data.xpos[body_id], yaw, -90.0)
    f = focal_px(fov_deg, frame.shape[0])
    w_world = R.reshape(3, 3) @ data.qvel[3:6]
    dist = ground_distance(cam_pos, cam_mat)
    vel = np.asarray(data.qvel[:3], dtype=float)
    jitter = math.radians(cond.gimbal_jitter_dps)
    blur = blur_vector(cam_pos, cam_mat, vel, float(w_world[2]), cond.exposure_s, f, dist, jitter)
    skew = blur_vector(cam_pos, cam_mat, vel, float(w_world[2]), cond.readout_s, f, dist, jitter)
    if truth is not None:
        truth.blur_px, truth.skew_px = blur, skew
    return apply_conditions(frame, cond, rng, blur=blur, skew=skew), blur
