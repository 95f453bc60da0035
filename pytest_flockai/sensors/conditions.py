"""Imaging conditions: what the flight and the weather do to a camera frame.

``fa.Conditions(...)`` (pass it to ``Camera(conditions=...)`` or
``Mission(conditions=...)``) applies, to every rendered frame, in the order
light reaches the sensor:

- **light** (``sun_elevation_deg``): the sun's elevation sets the scene's
  irradiance, ``sin(elevation)`` of the overhead sun's for direct light plus a
  diffuse sky share (``SKY_SHARE``), so dusk (a few degrees) is several times
  darker than noon;
- **sun direction and shadows** (``sun_azimuth_deg``, ``shadows``): with an
  azimuth (compass degrees the sun stands at: 0 north, 90 east) the frame is
  rendered under the sun shining from there at ``sun_elevation_deg``, with the
  same sun and sky shares as the brightness model (a horizontal face receives
  ``irradiance``; walls facing away from the sun and shadows only the sky's
  share), and auto-exposure aims at the level the scene has under an overhead
  sun; with ``shadows=True`` it casts shadows (MuJoCo's shadow map, 6 cm
  per texel within 60 m of the view centre), long at a low sun. Both need a
  render, not only a change of the pixels;
- **haze** (``visibility_m``): Koschmieder's law, extinction ``3.912 / V`` for a
  meteorological visibility V (the distance at which contrast falls to 2 %):
  each pixel is attenuated by ``exp(-beta d)`` over its distance ``d`` from the
  camera (MuJoCo's depth buffer) and filled with airlight;
- **motion blur** (``exposure_s``): the camera's own motion during the
  exposure, from the simulated physics: the image displacement of the scene
  point at the image centre between the start and the end of the exposure
  (the drone's velocity, its yaw rate, and the gimbal's residual jitter
  ``gimbal_jitter_dps``), applied as a linear kernel of that length, sub-pixel
  lengths included (a 0.7 px smear spreads each pixel over its neighbours). The
  scene point is where the optical axis meets the ground plane, whatever else
  is on (haze renders a depth buffer, but a rooftop or a person under the image
  centre would make the blur depend on it). At hover
  the blur is zero; a pass at speed ``v`` over flat ground at height ``h``
  blurs ``v * exposure_s * f / h`` pixels (``f`` the focal length in pixels);
- **exposure and sensor noise**: auto-exposure (``auto_exposure``) brings the
  mean level back to ``target_level`` (None: the level the scene has under the
  overhead sun, so ``Conditions()`` leaves a frame as rendered) by gain, up to
  ``max_gain``; the signal then
  collects shot noise (Poisson, ``full_well_e`` electrons at full scale) and
  read noise (``read_noise_e``), amplified by the gain, so a dark scene is a
  noisy one;
- **rolling shutter** (``readout_s``): the rows are read one after the other
  over ``readout_s`` (top first), so a moving camera sees the scene shift from
  row to row (a skew, the image displacement over the readout times the row's
  offset from mid-frame); the truth boxes move with their centre row;
- **weather** (``weather`` in rain, snow, spatter at ``severity`` 1-5):
  the standard image corruptions from albumentations (``sensors/weather.py``),
  drawn before the sensor adds its noise;
- **JPEG** stays on the radio link, as before.

Everything random draws from the mission seed; the frame's truth records the
blur length and direction (``truth.blur_px``) and the rolling-shutter skew
(``truth.skew_px``).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from numbers import Real

import cv2
import numpy as np

from .. import _check
from ..errors import ConfigError
from . import weather as _weather

#: share of the overhead-sun irradiance that the diffuse sky adds at any sun height
SKY_SHARE = 0.15
#: Koschmieder's constant: ln(1 / 0.02), contrast threshold 2 %
KOSCHMIEDER = 3.912
#: airlight (haze colour), linear RGB in [0, 1]: a bright neutral grey
AIRLIGHT = (0.82, 0.84, 0.86)


@dataclass(frozen=True)
class Conditions:
    exposure_s: float = 0.0
    sun_elevation_deg: float = 60.0
    visibility_m: float = math.inf
    auto_exposure: bool = True
    target_level: float | None = None
    max_gain: float = 16.0
    full_well_e: float = 6000.0
    read_noise_e: float = 3.0
    noise: bool = True
    gimbal_jitter_dps: float = 0.0
    sun_azimuth_deg: float | None = None
    shadows: bool = False
    readout_s: float = 0.0
    weather: str | None = None
    severity: int = 3

    def __post_init__(self):
        w = "Conditions"
        _check.non_negative("exposure_s", self.exposure_s, where=w)
        if self.exposure_s > 1.0:
            raise ConfigError(f"{w}: exposure_s = {self.exposure_s!r} is not allowed; expected "
                              f"a shutter time in [0, 1] s (e.g. 1/500 = 0.002)")
        _check.number("sun_elevation_deg", self.sun_elevation_deg, where=w, minimum=0.0,
                      maximum=90.0)
        for name in ("auto_exposure", "noise", "shadows"):
            if not isinstance(getattr(self, name), bool):
                raise ConfigError(f"{w}: {name} = {getattr(self, name)!r} is not allowed; "
                                  f"expected True or False")
        if isinstance(self.visibility_m, bool) or not isinstance(self.visibility_m, Real) or not (
                self.visibility_m > 0):
            raise ConfigError(f"{w}: visibility_m = {self.visibility_m!r} is not allowed; "
                              f"expected a distance > 0 m (inf: clear air)")
        if self.target_level is not None:
            _check.number("target_level", self.target_level, where=w, minimum=0.01, maximum=0.99)
        _check.number("max_gain", self.max_gain, where=w, minimum=1.0, maximum=1e4)
        _check.positive("full_well_e", self.full_well_e, where=w)
        _check.non_negative("read_noise_e", self.read_noise_e, where=w)
        _check.non_negative("gimbal_jitter_dps", self.gimbal_jitter_dps, where=w)
        if self.sun_azimuth_deg is not None:
            _check.number("sun_azimuth_deg", self.sun_azimuth_deg, where=w, minimum=0.0,
                          maximum=360.0)
        _check.number("readout_s", self.readout_s, where=w, minimum=0.0, maximum=0.2)
        _weather.check(self.weather, self.severity, w)

    @property
    def irradiance(self) -> float:
        """Scene irradiance relative to an overhead sun."""
        return (math.sin(math.radians(self.sun_elevation_deg)) + SKY_SHARE) / (1.0 + SKY_SHARE)

    @property
    def sun_dir(self):
        """The direction sunlight travels (x east, y north, z up), or None: the world's
        own sun (no azimuth given)."""
        if self.sun_azimuth_deg is None:
            return None
        az, el = math.radians(self.sun_azimuth_deg), math.radians(max(self.sun_elevation_deg, 0.5))
        return (-math.sin(az) * math.cos(el), -math.cos(az) * math.cos(el), -math.sin(el))

    @property
    def relights(self) -> bool:
        """True when the scene must be rendered under this sun (direction, shadows)."""
        return self.shadows or self.sun_azimuth_deg is not None

    @property
    def extinction_per_m(self) -> float:
        """Haze extinction coefficient (1/m) from the visibility (Koschmieder); 0 in clear air."""
        return KOSCHMIEDER / self.visibility_m if math.isfinite(self.visibility_m) else 0.0

    @property
    def needs_depth(self) -> bool:
        """Whether the frames need per-pixel depth (haze)."""
        return self.extinction_per_m > 0.0

    def to_dict(self) -> dict:
        """JSON-ready description for the flight's scenario."""
        return {k: (None if isinstance(v, float) and math.isinf(v) else v)
                for k, v in asdict(self).items()}


def blur_vector(cam_pos, cam_mat, velocity, yaw_rate, exposure_s, focal_px, distance_m,
                jitter_rad_s=0.0):
    """(du, dv) pixels the image centre's scene point moves during the exposure.

    The camera moves by ``velocity * T`` and turns about the world vertical by
    ``yaw_rate * T`` (plus ``jitter`` about its own axes); the scene point is the
    one at ``distance_m`` along the optical axis.
    """
    if exposure_s <= 0.0:
        return 0.0, 0.0
    R = np.asarray(cam_mat, dtype=float).reshape(3, 3)
    p0 = np.asarray(cam_pos, dtype=float) - R[:, 2] * distance_m      # looks along -z
    c1 = np.asarray(cam_pos, dtype=float) + np.asarray(velocity, dtype=float) * exposure_s
    a = yaw_rate * exposure_s
    Rz = np.array([[math.cos(a), -math.sin(a), 0.0], [math.sin(a), math.cos(a), 0.0], [0, 0, 1.0]])
    R1 = Rz @ R
    c = (p0 - c1) @ R1
    depth = -c[2]
    du = focal_px * c[0] / depth
    dv = -focal_px * c[1] / depth
    j = jitter_rad_s * exposure_s * focal_px
    return float(du + j), float(dv + j)


#: pixels: blur shorter than this is not applied (a smear of 1/100 px changes no uint8 pixel)
MIN_BLUR_PX = 0.01


def motion_kernel(du: float, dv: float) -> np.ndarray | None:
    """A normalised line kernel of the blur, sub-pixel lengths included (None when
    under ``MIN_BLUR_PX``): the line's samples are spread bilinearly over the pixels."""
    length = math.hypot(du, dv)
    if length < MIN_BLUR_PX:
        return None
    n = max(3, int(math.ceil(length)) | 1)
    k = np.zeros((n, n), np.float32)
    c = n // 2
    steps = max(2, int(math.ceil(length * 4)))
    for s in np.linspace(-0.5, 0.5, steps):
        x, y = c + s * du, c + s * dv
        x0, y0 = int(math.floor(x)), int(math.floor(y))
        fx, fy = x - x0, y - y0
        for xi, yi, w in ((x0, y0, (1 - fx) * (1 - fy)), (x0 + 1, y0, fx * (1 - fy)),
                          (x0, y0 + 1, (1 - fx) * fy), (x0 + 1, y0 + 1, fx * fy)):
            if 0 <= xi < n and 0 <= yi < n:
                k[yi, xi] += w
    return k / k.sum()


def rolling_shift(frame: np.ndarray, skew) -> np.ndarray:
    """The frame as a rolling shutter reads it: row r shows the scene shifted by
    ``skew * (r / (H - 1) - 0.5)`` pixels (skew: the image displacement over the readout)."""
    du, dv = skew
    if math.hypot(du, dv) < 0.25:
        return frame
    h, w = frame.shape[:2]
    f = (np.arange(h, dtype=np.float32) / max(h - 1, 1) - 0.5)[:, None]
    xx = np.broadcast_to(np.arange(w, dtype=np.float32)[None, :], (h, w))
    yy = np.broadcast_to(np.arange(h, dtype=np.float32)[:, None], (h, w))
    return cv2.remap(frame, (xx - du * f).astype(np.float32), (yy - dv * f).astype(np.float32),
                     cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)


def shift_boxes(boxes: np.ndarray, skew, height: int) -> np.ndarray:
    """(N, 4) x0, y0, x1, y1 boxes moved as ``rolling_shift`` moves their centre row."""
    if len(boxes) == 0 or math.hypot(*skew) < 0.25:
        return boxes
    b = np.array(boxes, dtype=float)
    f = ((b[:, 1] + b[:, 3]) / 2.0 / max(height - 1, 1) - 0.5)
    b[:, [0, 2]] += (skew[0] * f)[:, None]
    b[:, [1, 3]] += (skew[1] * f)[:, None]
    return b


def apply(frame: np.ndarray, cond: Conditions, rng, *, distance=None, blur=(0.0, 0.0),
          skew=(0.0, 0.0)) -> np.ndarray:
    """The frame as the sensor records it (see the module docstring). ``frame``:
    uint8 RGB as rendered under an overhead sun; ``distance``: (H, W) metres
    from the camera (needed for haze); ``blur``: (du, dv) pixels over the
    exposure; ``skew``: (du, dv) pixels over the rolling-shutter readout."""
    frame = rolling_shift(frame, skew)
    if distance is not None:
        distance = rolling_shift(distance, skew)
    img: np.ndarray = frame.astype(np.float32) / 255.0
    if cond.sun_azimuth_deg is None:      # rendered under the overhead sun: dim it here
        target = cond.target_level if cond.target_level is not None else float(img.mean())
        img *= cond.irradiance
    else:                                 # rendered under this sun: the light is in the frame
        target = (cond.target_level if cond.target_level is not None
                  else min(float(img.mean()) / cond.irradiance, 1.0))
    beta = cond.extinction_per_m
    if beta > 0.0:
        if distance is None:
            raise ConfigError("Conditions: haze needs the depth of each pixel")
        t = np.exp(-beta * np.minimum(distance, 1e4)).astype(np.float32)[..., None]
        img = img * t + np.asarray(AIRLIGHT, np.float32) * cond.irradiance * (1.0 - t)
    if cond.weather is not None:
        img = _weather.apply(img, cond.weather, cond.severity, rng)
    k = motion_kernel(*blur)
    if k is not None:
        img = cv2.filter2D(img, -1, k, borderType=cv2.BORDER_REFLECT)
    gain = 1.0
    if cond.auto_exposure:
        mean = float(img.mean())
        gain = min(cond.max_gain, target / mean) if mean > 1e-6 else cond.max_gain
    if cond.noise:      # electrons collected, shot and read noise, then the gain
        e = np.clip(img, 0.0, None) * cond.full_well_e
        e += rng.standard_normal(e.shape).astype(np.float32) * np.sqrt(e + cond.read_noise_e ** 2)
        img = e / cond.full_well_e
    img = img * gain
    return np.clip(img * 255.0 + 0.5, 0, 255).astype(np.uint8)
