"""Area division: a survey area split among N drones, one zig-zag strip each.

``survey(area, n, ...)`` cuts ``area`` = ((x0, y0), (x1, y1)) into ``n`` strips
of equal width across y (legs along x, as ``pilots.ZigZag`` flies them) and
returns ``n`` ``FleetDrone``-ready parts: a ``ZigZag`` pilot over each strip and
a pad just outside the area below the strip's first corner, so every drone
takes off from, returns to and lands at its own pad. Strips hold a whole
number of legs (``spacing`` apart) where possible, so N strips fly the same
legs one drone would.
"""

from __future__ import annotations

import math

from .. import _check
from ..control.pilots import ZigZag
from ..errors import ConfigError
from ..world import World
from . import pads as _pads
from .fleet import PAD_CLEARANCE_M, MAX_DRONES


def strips(area, n: int, spacing: float) -> list:
    """``n`` sub-areas ((x0, y0), (x1, y1)) of ``area``, split across y; the legs
    (``spacing`` apart) are shared out as evenly as whole legs allow."""
    if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= MAX_DRONES:
        raise ConfigError(f"survey: n = {n!r} is not allowed; expected an integer from 1 to "
                          f"{MAX_DRONES}")
    spacing = _check.positive("spacing", spacing, where="survey")
    x0, y0, x1, y1 = _check.area(area, where="survey")
    x0, x1 = sorted((x0, x1))
    y0, y1 = sorted((y0, y1))
    rows = [y0 + k * spacing for k in range(int(math.ceil((y1 - y0) / spacing - 1e-9)))] + [y1]
    legs = len(rows)                                  # the legs one ZigZag drone flies
    if legs < 2 * n:
        raise ConfigError(f"survey: area = {area!r} has {legs} legs {spacing:g} m apart, fewer "
                          f"than 2 per drone for n = {n}; allowed: n <= {legs // 2} (or a "
                          f"smaller spacing)")
    out = []
    first = 0
    for k in range(n):
        count = legs // n + (1 if k < legs % n else 0)
        out.append(((x0, rows[first]), (x1, rows[first + count - 1])))
        first += count
    return out


def survey(area, n: int, *, altitude: float = 30.0, spacing: float = 15.0, speed: float = 8.0,
           pad_offset_m: float = 5.0, world=None) -> list:
    """``n`` (pilot, pad) pairs covering ``area``: ``ZigZag`` over each strip and a pad
    ``pad_offset_m`` before the strip's first corner (x0 - offset, strip's y0). With
    ``world``, a pad that would stand in or against a building is moved to the nearest
    free ground (``pads.free_pad``); pass the world the fleet flies in."""
    pad_offset_m = _check.positive("pad_offset_m", pad_offset_m, where="survey")
    if world is not None and not isinstance(world, World):
        raise ConfigError(f"survey: world = {world!r} is not allowed; expected None or a "
                          f"fa.World")
    parts = strips(area, n, spacing)
    obs = _pads.obstacles(world)
    out: list = []
    for k, sub in enumerate(parts):
        (x0, lo), _ = sub
        pad = (x0 - pad_offset_m, lo)
        if k and math.dist(pad, out[-1][1]) < PAD_CLEARANCE_M:
            raise ConfigError(f"survey: strips of area = {area!r} are closer than the pads' "
                              f"{PAD_CLEARANCE_M:g} m; allowed: fewer drones or a larger area")
        if len(obs):
            free = _pads.free_pad(obs, pad, [p for _, p in out], PAD_CLEARANCE_M)
            if free is None:
                raise ConfigError(f"survey: no free ground within "
                                  f"{_pads.SEARCH_RADIUS_M:g} m of drone {k}'s pad "
                                  f"({pad[0]:g}, {pad[1]:g}); allowed: an area with open "
                                  f"ground beside it")
            pad = free
        out.append((ZigZag(sub, altitude=altitude, spacing=spacing, speed=speed), pad))
    return out
