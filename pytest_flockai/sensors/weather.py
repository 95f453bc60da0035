"""Weather corruptions of a frame at a severity 1-5, through albumentations.

The standard corruption set of a field (ImageNet-C style: rain, snow, water
on the lens) comes from albumentations (MIT licence, built on
``opencv-python-headless``; the older ``imagecorruptions`` package requires the
GUI ``opencv-python`` and clashes with it). It is an optional dependency:
``pip install 'pytest-flockai[weather]'``.

Fog is not among them: ``Conditions(visibility_m=...)`` puts haze where the
depth buffer says it belongs (Koschmieder's law, about a millisecond a frame),
while albumentations' image-space ``RandomFog`` ignores depth and cost 0.1-1.8 s
per 320x240 frame here.

Severity maps to each transform's own parameters (``SEVERITY``): 1 is light, 5
the heaviest the transform offers. Each frame's draw comes from the flight's
random stream, so the same seed gives the same rain.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..errors import ConfigError

WEATHER = ("rain", "snow", "spatter")
#: per weather, per severity 1..5: keyword arguments of the albumentations transform
SEVERITY: dict[str, list[dict[str, Any]]] = {
    "rain": [dict(rain_type="drizzle", brightness_coefficient=0.9),
             dict(rain_type="drizzle", brightness_coefficient=0.8, drop_width=2),
             dict(rain_type="heavy", brightness_coefficient=0.75),
             dict(rain_type="heavy", brightness_coefficient=0.7, drop_width=2),
             dict(rain_type="torrential", brightness_coefficient=0.6)],
    "snow": [dict(snow_point_range=(s, s), brightness_coeff=2.0)
             for s in (0.05, 0.1, 0.18, 0.26, 0.35)],
    "spatter": [dict(mode="rain", cutout_threshold=(t, t), intensity=(i, i))
                for t, i in ((0.72, 0.3), (0.70, 0.45), (0.68, 0.6), (0.66, 0.7), (0.64, 0.8))],
}
_TRANSFORMS = {"rain": "RandomRain", "snow": "RandomSnow", "spatter": "Spatter"}
_cache: dict = {}


def check(weather, severity, where: str = "Conditions") -> None:
    if weather is None:
        return
    if weather not in WEATHER:
        raise ConfigError(f"{where}: weather = {weather!r} is not allowed; expected None or one "
                          f"of {', '.join(map(repr, WEATHER))}")
    if isinstance(severity, bool) or not isinstance(severity, (int, np.integer)) \
            or not 1 <= severity <= 5:
        raise ConfigError(f"{where}: severity = {severity!r} is not allowed; expected an "
                          f"integer 1..5")


def transform(weather: str, severity: int):
    """The albumentations pipeline of a weather at a severity (built once)."""
    key = (weather, int(severity))
    if key not in _cache:
        try:
            import albumentations as A
        except ImportError:
            raise ConfigError(f"Conditions: weather = {weather!r} needs albumentations; install "
                              f"it with pip install 'pytest-flockai[weather]'") from None
        t = getattr(A, _TRANSFORMS[weather])(p=1.0, **SEVERITY[weather][int(severity) - 1])
        _cache[key] = A.Compose([t], seed=0)
    return _cache[key]


def apply(img: np.ndarray, weather: str, severity: int, rng) -> np.ndarray:
    """img: float32 RGB in [0, 1]; returns the same with the weather drawn over it."""
    t = transform(weather, severity)
    t.set_random_seed(int(rng.integers(2 ** 31 - 1)))
    u8 = np.clip(img * 255.0 + 0.5, 0, 255).astype(np.uint8)
    return t(image=u8)["image"].astype(np.float32) / 255.0
