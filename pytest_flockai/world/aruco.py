"""Fiducial markers on the ground: ArUco tags rendered in the world, for precision landing.

``actors.Marker(x, y, size_m=1.5, marker_id=0)`` lies flat on the ground (a 2 cm slab, no
collision) with the tag drawn by OpenCV (``cv2.aruco.generateImageMarker``) as its
texture, a white quiet zone of one cell around it. Markers ride in
``Mission(actors=[...])`` with the moving people and cars (they stand still and are
not objects of the detection truth). ``ml.MarkerDetector`` finds them in frames.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import cv2
import mujoco
import numpy as np

from .._io import atomic_write

DICTIONARIES = ("DICT_4X4_50", "DICT_5X5_50", "DICT_6X6_50", "DICT_APRILTAG_36h11")
CELLS = {"DICT_4X4_50": 4, "DICT_5X5_50": 5, "DICT_6X6_50": 6, "DICT_APRILTAG_36h11": 6}
TEXEL_PER_CELL = 16
THICKNESS_M = 0.02
#: m: height of a marker's top face (above the streets' 4 cm)
TOP_Z = 0.045


def aruco_dictionary(name: str):
    """The OpenCV predefined dictionary ``name`` (one of DICTIONARIES)."""
    return cv2.aruco.getPredefinedDictionary(getattr(cv2.aruco, name))


def marker_image(dictionary: str, marker_id: int) -> np.ndarray:
    """The texture of a tag: the tag with a one-cell white quiet zone, RGB uint8,
    ``TEXEL_PER_CELL`` texels per cell."""
    px = (CELLS[dictionary] + 2) * TEXEL_PER_CELL
    tag = cv2.aruco.generateImageMarker(aruco_dictionary(dictionary), int(marker_id), px)
    full = np.full((px + 2 * TEXEL_PER_CELL,) * 2, 255, np.uint8)
    full[TEXEL_PER_CELL:-TEXEL_PER_CELL, TEXEL_PER_CELL:-TEXEL_PER_CELL] = tag
    return np.ascontiguousarray(np.repeat(full[:, :, None], 3, axis=2))


def marker_file(dictionary: str, marker_id: int) -> Path:
    """A PNG of the tag's texture in this user's temporary folder (written once,
    atomically): a texture from a file keeps the model's spec writable as MJCF."""
    folder = Path(tempfile.gettempdir()) / f"pytest-flockai-markers-{os.getuid()}"
    path = folder / f"{dictionary}-{int(marker_id)}-{TEXEL_PER_CELL}.png"
    if not path.exists():
        folder.mkdir(parents=True, exist_ok=True)
        ok, png = cv2.imencode(".png", marker_image(dictionary, marker_id)[:, :, ::-1])
        atomic_write(path, lambda fh: fh.write(png.tobytes()), text=False)
    return path


def add_marker(spec, name: str, centre, size_m: float, dictionary: str, marker_id: int,
               yaw_deg: float = 0.0) -> None:
    """A textured slab on the ground of the world body: the tag's black square
    ``size_m`` wide, centred at ``centre`` (x, y), turned by ``yaw_deg``."""
    spec.add_texture(name=name, type=mujoco.mjtTexture.mjTEXTURE_2D,
                     file=str(marker_file(dictionary, marker_id)))
    mat = spec.add_material(name=name, specular=0.0, shininess=0.0, reflectance=0.0)
    mat.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = name
    half = 0.5 * size_m * (CELLS[dictionary] + 4) / (CELLS[dictionary] + 2)
    yaw = np.radians(yaw_deg)
    spec.worldbody.add_geom(name=name, type=mujoco.mjtGeom.mjGEOM_BOX,
                            pos=[centre[0], centre[1], TOP_Z - THICKNESS_M / 2],
                            quat=[np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)],
                            size=[half, half, THICKNESS_M / 2], material=name,
                            contype=0, conaffinity=0, group=0)


__all__ = ["CELLS", "DICTIONARIES", "TOP_Z", "add_marker", "aruco_dictionary", "marker_file",
           "marker_image"]
