"""The README's imaging-conditions picture: one view of the city, ideal, blurred
by a fast pass, at dusk, in haze, with a low sun's shadows, through a rolling
shutter, in rain and in snow. ``MUJOCO_GL=egl python docs/conditions_figure.py``"""

from pathlib import Path

import cv2
import numpy as np

import pytest_flockai as fa

HERE = Path(__file__).resolve().parent
world = fa.World.urban(seed=7, size=(120.0, 120.0), people=60, crowds=[(20.0, 10.0, 25, 3.0)],
                       vehicles=20, max_building_height=25.0, figures="articulated")
views = fa.sensors.ViewSet(world, [(20.0, 10.0, 30.0, 0.3)], {"fov_deg": 51.0})
fast = (15.0, 0.0, 0.0)
panels = [("ideal", views.ideal()[0][0]),
          ("15 m/s, 1/30 s shutter", views.under(fa.Conditions(exposure_s=1 / 30),
                                                 velocity=fast)[0][0]),
          ("dusk: sun 2 deg", views.under(fa.Conditions(sun_elevation_deg=2.0))[0][0]),
          ("haze: visibility 150 m", views.under(fa.Conditions(visibility_m=150.0))[0][0]),
          ("sun in the WSW at 25 deg, shadows",
           views.under(fa.Conditions(sun_azimuth_deg=250.0, sun_elevation_deg=25.0,
                                     shadows=True))[0][0]),
          ("rolling shutter 30 ms, 15 m/s", views.under(fa.Conditions(readout_s=0.03),
                                                        velocity=fast)[0][0]),
          ("rain, severity 3", views.under(fa.Conditions(weather="rain", severity=3))[0][0]),
          ("snow, severity 3", views.under(fa.Conditions(weather="snow", severity=3))[0][0])]
tiles = []
for label, img in panels:
    img = img.copy()
    cv2.putText(img, label, (6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (255, 255, 255), 1, cv2.LINE_AA)
    tiles.append(img)
grid = np.vstack([np.hstack(tiles[i:i + 4]) for i in (0, 4)])
cv2.imwrite(str(HERE / "img" / "conditions.png"), cv2.cvtColor(grid, cv2.COLOR_RGB2BGR))
print("wrote", HERE / "img" / "conditions.png")

close = fa.World.scene(people=[(x, y) for x in (-3.0, -1.5, 0.0, 1.5, 3.0) for y in (-1.5, 0.0, 1.5)],
                       vehicles=[(0.0, 6.0, 0.0), (0.0, -6.0, 0.6)], figures="articulated")
side = fa.sensors.render_views(close, [(0.0, -14.0, 3.0, np.pi / 2)],
                               {"fov_deg": 50.0, "width": 480, "height": 320, "pitch_deg": -12.0})
top = fa.sensors.ViewSet(close, [(0.0, 0.0, 14.0, 0.0)],
                         {"fov_deg": 60.0, "width": 480, "height": 320}).under(
    fa.Conditions(sun_azimuth_deg=250.0, sun_elevation_deg=35.0, shadows=True, noise=False))
pair = np.hstack([side[0][0], top[0][0]])
cv2.imwrite(str(HERE / "img" / "figures.png"), cv2.cvtColor(pair, cv2.COLOR_RGB2BGR))
print("wrote", HERE / "img" / "figures.png")
