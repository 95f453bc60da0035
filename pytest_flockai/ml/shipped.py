"""The models shipped inside the package: ``fa.ml.shipped("detector")``.

The ``.onnx`` files are package data (``pytest_flockai/ml/shipped_models/``), so an
installed package has them; the recipes that trained them, their results and
their limits stay in the repository's ``fixtures/models/`` (README.md there),
whose files are the same bytes.

- ``detector``: people and vehicles, YOLOv8-style raw head (decoded by
  ``ml.detections``), trained on this project's rendered worlds (``make_detector.py``);
- ``detector_haze``: the same recipe with imaging conditions (haze, blur, dusk)
  in its training frames;
- ``crowd_cnn``: the accurate crowd counter (density map, 525.6 M MACs at 320x240);
- ``crowd_tiny``: the cheap crowd counter (3.9 M MACs).
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from ..errors import ConfigError
from .models import OnnxModel

#: name -> (file, what it is)
SHIPPED = {
    "detector": ("detector.onnx", "people and vehicles, YOLOv8-style head (evaluate='detection')"),
    "detector_haze": ("detector_haze.onnx", "the detector trained with haze, blur and dusk"),
    "crowd_cnn": ("crowd_cnn.onnx", "crowd counting density map, accurate (evaluate='count')"),
    "crowd_tiny": ("crowd_tiny.onnx", "crowd counting density map, cheap (evaluate='count')"),
}


def shipped_path(name: str) -> Path:
    """The installed file of the shipped model ``name``."""
    if name not in SHIPPED:
        raise ConfigError(f"shipped model = {name!r} is not allowed; allowed: "
                          + ", ".join(f"{k!r} ({v[1]})" for k, v in SHIPPED.items()))
    return Path(str(resources.files(__package__) / "shipped_models" / SHIPPED[name][0]))


def shipped(name: str, **kw) -> OnnxModel:
    """The shipped model ``name`` as an ``OnnxModel`` (``kw`` as there; named after it)."""
    kw.setdefault("name", name)
    return OnnxModel(shipped_path(name), **kw)
