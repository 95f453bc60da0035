"""Fence geometry shared by ``Cockpit`` (goto/orbit targets refused outside the world or
a geofence) and ``Geofence`` (policy/geofence.py): a world's bounds, a point in a
polygon, and why a target is refused."""

from __future__ import annotations

import math

from .. import limits


def world_box(world) -> list:
    """The corners of ``world``'s bounds (its ``size`` centred on the origin)."""
    size = getattr(world, "size", None) if world is not None else None
    hx, hy = ((size[0] / 2, size[1] / 2) if size is not None
              else (limits.MAX_EXTENT_M, limits.MAX_EXTENT_M))
    return [(-hx, -hy), (hx, -hy), (hx, hy), (-hx, hy)]


def inside(poly, x: float, y: float) -> bool:
    """Whether (x, y) lies inside the polygon ``poly`` (even-odd rule; edges inside)."""
    n, hit = len(poly), False
    for i in range(n):
        (x0, y0), (x1, y1) = poly[i], poly[(i + 1) % n]
        if (y0 > y) != (y1 > y):
            xc = x0 + (y - y0) * (x1 - x0) / (y1 - y0)
            if x <= xc:
                hit = not hit
    return hit or any(math.isclose(x, px) and math.isclose(y, py) for px, py in poly)


def refusal(cockpit, x: float, y: float, z: float | None = None, radius: float = 0.0) -> str | None:
    """Why a target at (x, y, z) (a circle of ``radius`` around it) is refused, or None:
    outside the world, or outside (or above) a ``Geofence`` of the flight."""
    run = cockpit._run
    fences: list[tuple[str, list, float | None]] = [
        ("the world", world_box(getattr(run.plan, "world", None)), None)]
    fences += [(f"geofence {p.name!r}", p.fence, p.ceiling_m)
               for p in getattr(run, "policies", ()) if getattr(p, "is_geofence", False)]
    pts = [(x, y)] if radius <= 0 else [
        (x + radius * math.cos(a), y + radius * math.sin(a))
        for a in (i * math.pi / 4 for i in range(8))]
    for what, poly, ceiling in fences:
        if not all(inside(poly, *p) for p in pts):
            return f"({x:g}, {y:g}) is outside {what}"
        if ceiling is not None and z is not None and z - cockpit._st.home[2] > ceiling:
            return f"altitude {z:g} m is above {what}'s ceiling of {ceiling:g} m"
    return None


__all__ = ["inside", "refusal", "world_box"]
