"""The geofence of an app's flight, as PX4's navigator checks it: the fence the app uploaded
(mission protocol, MAV_MISSION_TYPE_FENCE, ``mission_protocol``) and the parameters GF_MAX_HOR_DIST
and GF_MAX_VER_DIST (metres from home, horizontally and above it; 0: no limit).

A position is inside when it lies in at least one inclusion polygon or circle (when there
is one), in no exclusion polygon or circle, and within both distances (the rule of PX4's
``Geofence::isInsidePolygonOrCircle``, src/modules/navigator/geofence.cpp).
A polygon is a run of MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION (or _EXCLUSION) items whose
param1 is the polygon's vertex count; a circle is one MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION (or
_EXCLUSION) item, its radius in param1 (MAVLink common message set). The check is on the
drone's estimated position at the autopilot's 25 Hz, without PX4's experimental
``GF_PREDICT`` (off by default); the autopilot acts on a breach as ``GF_ACTION`` says
(``Autopilot._geofence``).
"""

from __future__ import annotations

import math

from pymavlink.dialects.v20 import common as M

from ..policy.fence import inside

POLY_IN = M.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION
POLY_OUT = M.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION
CIRCLE_IN = M.MAV_CMD_NAV_FENCE_CIRCLE_INCLUSION
CIRCLE_OUT = M.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION
ITEMS = {POLY_IN, POLY_OUT, CIRCLE_IN, CIRCLE_OUT}
#: GF_ACTION's values (PX4 parameter reference; default 2)
ACTIONS = {0: "none", 1: "warn", 2: "hold", 3: "return", 4: "terminate", 5: "land"}


def _shapes(items: list) -> tuple[list, tuple[int, str] | None]:
    """``items`` grouped into shapes, [(command, [its items])], and (seq, why) of the first
    item that makes them not a geofence (None: they are one; the shapes before it)."""
    out: list = []
    i = 0
    while i < len(items):
        it = items[i]
        n = it["p"][0]
        if it["command"] in (CIRCLE_IN, CIRCLE_OUT):
            if not (math.isfinite(n) and n > 0):
                return out, (it["seq"], f"a circle's radius (param1) is {n!r}; allowed: > 0 m")
            n = 1
        elif not (math.isfinite(n) and n == int(n) and n >= 3):
            return out, (it["seq"], f"a polygon's vertex count (param1) is {n!r}; allowed: a "
                                    f"whole number >= 3")
        run = items[i:i + int(n)]
        k = next((j for j, v in enumerate(run) if v["command"] != it["command"]
                  or v["p"][0] != it["p"][0]), len(run))       # its vertices in a row
        if k < n:
            return out, (it["seq"], f"a polygon of {int(n)} vertices has {k} items of its kind "
                                    f"in a row; allowed: its vertices one after the other")
        out.append((it["command"], run))
        i += int(n)
    return out, None


def check(items: list) -> tuple[int, str] | None:
    """(seq, why) of the first item that makes ``items`` not a geofence, or None."""
    return _shapes(items)[1]


class Boundary:
    """The uploaded fence's shapes in the world frame (x east, y north, m), from ``items``
    (checked by ``check``) and ``geo`` (``frames.Geo``)."""

    def __init__(self, items: list, geo):
        self.polygons: list[tuple[bool, list]] = []      # (inclusion, [(x, y), ...])
        self.circles: list[tuple[bool, float, float, float]] = []   # (inclusion, x, y, r)
        self.home = geo.home
        for cmd, run in _shapes(items)[0]:
            pts = [geo.to_world(v["x"], v["y"], 0.0)[:2] for v in run]
            if cmd in (CIRCLE_IN, CIRCLE_OUT):
                self.circles.append((cmd == CIRCLE_IN, *pts[0], float(run[0]["p"][0])))
            else:
                self.polygons.append((cmd == POLY_IN, pts))

    @property
    def shapes(self) -> int:
        """How many polygons and circles the fence has."""
        return len(self.polygons) + len(self.circles)

    def breach(self, x: float, y: float, z: float, max_hor_m: float = 0.0,
               max_ver_m: float = 0.0) -> str | None:
        """Why the point (x, y, z) is outside the geofence, or None when it is inside."""
        hx, hy, hz = self.home
        if max_ver_m > 0 and z - hz > max_ver_m:
            return f"{z - hz:.1f} m above home, over GF_MAX_VER_DIST = {max_ver_m:g} m"
        if max_hor_m > 0 and math.hypot(x - hx, y - hy) > max_hor_m:
            return (f"{math.hypot(x - hx, y - hy):.1f} m from home, over GF_MAX_HOR_DIST = "
                    f"{max_hor_m:g} m")
        shapes = [(inc, inside(pts, x, y)) for inc, pts in self.polygons]
        shapes += [(inc, math.hypot(x - cx, y - cy) <= r) for inc, cx, cy, r in self.circles]
        if any(hit for inc, hit in shapes if not inc):
            return "inside an exclusion zone of the geofence"
        if any(inc for inc, _ in shapes) and not any(hit for inc, hit in shapes if inc):
            return "outside the geofence's inclusion zones"
        return None


__all__ = ["ACTIONS", "ITEMS", "Boundary", "check"]
