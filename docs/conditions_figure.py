"""The README's imaging-conditions picture: one view of the city, ideal, blurred
by a fast pass, at dusk and in haze. ``MUJOCO_GL=egl python docs/conditions_figure.py``"""

from pathlib import Path

import cv2
import numpy as np

import pytest_flockai as fa

HERE = Path(__file__).resolve().parent
world = fa.World.urban(seed=7, size=(120.0, 120.0), people=60, crowds=[(20.0, 10.0, 25, 3.0)],
                       vehicles=20, max_building_height=25.0)
views = fa.sensors.ViewSet(world, [(20.0, 10.0, 30.0, 0.3)], {"fov_deg": 51.0})
panels = [("ideal", views.ideal()[0][0]),
          ("15 m/s, 1/30 s shutter", views.under(fa.Conditions(exposure_s=1 / 30),
                                                 velocity=(15.0, 0.0, 0.0))[0][0]),
          ("dusk: sun 2 deg", views.under(fa.Conditions(sun_elevation_deg=2.0))[0][0]),
          ("haze: visibility 150 m", views.under(fa.Conditions(visibility_m=150.0))[0][0])]
tiles = []
for label, img in panels:
    img = img.copy()
    cv2.putText(img, label, (6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1, cv2.LINE_AA)
    tiles.append(img)
grid = np.vstack([np.hstack(tiles[:2]), np.hstack(tiles[2:])])
cv2.imwrite(str(HERE / "img" / "conditions.png"), cv2.cvtColor(grid, cv2.COLOR_RGB2BGR))
print("wrote", HERE / "img" / "conditions.png")
