"""Routes a diverted drone hands over (``GroundStation`` with ``share``): the tail of a plan
as long as a time away would fly, and a route cut into contiguous parts."""

from __future__ import annotations

import math


def tail(points: list, length: float):
    """``points`` (a route) cut ``length`` metres before its end: (head, tail); the cut
    point ends the head and starts the tail."""
    left = sum(math.dist(a, b) for a, b in zip(points, points[1:])) - length
    if left <= 0:
        return points[:1], points
    for i, (a, b) in enumerate(zip(points, points[1:])):
        d = math.dist(a, b)
        if left <= d:
            f = left / d
            cut = tuple(a[j] + f * (b[j] - a[j]) for j in range(3))
            return list(points[:i + 1]) + [cut], [cut] + list(points[i + 1:])
        left -= d
    return points, points[-1:]


def cut(points: list, n: int) -> list:
    """``points`` (a route) cut into at most ``n`` contiguous routes of about equal leg
    count; a cut point ends one part and starts the next (that leg is not lost)."""
    legs = len(points) - 1
    n = min(n, legs)
    if n < 1:
        return [points] if points else []
    bounds = [round(i * legs / n) for i in range(n + 1)]
    return [points[a:b + 1] for a, b in zip(bounds, bounds[1:])]


__all__ = ["cut", "tail"]
