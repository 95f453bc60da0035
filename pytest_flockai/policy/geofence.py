"""Geofence: where the drone may fly, and what it does when it would leave.

``Geofence(polygon=None, ceiling_m=None, action="hold")`` is a policy: the fence is the
mission world's bounds (its ``size``, centred on the origin; worlds without one:
``limits.MAX_EXTENT_M``) or the user's ``polygon`` [(x, y), ...] (at least three
corners), with an optional ``ceiling_m`` (metres above the ground). Every ``period_s`` it
predicts where the drone would stop if it braked now (speed^2 / (2 x the stage
machine's acceleration), as PX4's ``GF_PREDICT``) and, when that point or the drone is
outside, it is a breach: an event ``{"kind": "geofence_breach", ...}``, the KPI
``geofence_breaches`` and the ``action``, as PX4's ``GF_ACTION``: ``"warn"`` (event
only), ``"hold"`` (hover where it is), ``"return_home"`` or ``"land"``. A breach is
counted once until the drone is back inside.

Independently of this policy, a policy's ``goto`` or ``orbit`` whose target lies outside
the world (or outside a ``Geofence`` of the mission) is refused: a ``policy_refused``
event with ``reason``, and the action returns False.
"""

from __future__ import annotations

import math

from .. import _check
from .. import kpis as _kpis
from ..errors import ConfigError
from .base import Policy
from .fence import inside, refusal, world_box

#: PX4 GF_ACTION's choices that apply here (1 warning, 2 hold, 3 return, 5 land)
ACTIONS = ("warn", "hold", "return_home", "land")


class Geofence(Policy):
    """Keep the drone inside a fence (module docstring)."""

    is_geofence = True          # fence.refusal: goto/orbit targets outside it are refused

    def __init__(self, polygon=None, *, ceiling_m: float | None = None, action: str = "hold",
                 name: str = "geofence", period_s: float = 0.1) -> None:
        super().__init__(name, period_s)
        where = f"policy {self.name!r}"
        self.polygon = None
        if polygon is not None:
            try:
                pts = [tuple(float(v) for v in p) for p in polygon]
            except (TypeError, ValueError):
                raise ConfigError(f"{where}: polygon = {polygon!r} is not allowed; expected "
                                  f"[(x, y), ...] with at least 3 corners") from None
            if len(pts) < 3 or any(len(p) != 2 or not all(map(math.isfinite, p)) for p in pts):
                raise ConfigError(f"{where}: polygon = {polygon!r} is not allowed; expected "
                                  f"[(x, y), ...] with at least 3 finite corners")
            self.polygon = pts
        self.ceiling_m = None if ceiling_m is None else _check.positive(
            "ceiling_m", ceiling_m, where=where)
        self.action = _check.choice("action", action, ACTIONS, where=where)
        self.fence: list = self.polygon or []

    def start(self, run) -> None:
        self.fence = self.polygon or world_box(getattr(run.plan, "world", None))
        self.breaches = 0
        self._out = False

    def decide(self, t, drone) -> None:
        x, y, z = drone.position
        vx, vy, _ = drone.velocity
        v = math.hypot(vx, vy)
        stop = v / (2.0 * max(drone._stages.accel, 1e-6))      # s of travel to stop
        px, py = x + vx * stop, y + vy * stop
        high = self.ceiling_m is not None and z - drone._st.home[2] > self.ceiling_m
        out = high or not inside(self.fence, px, py) or not inside(self.fence, x, y)
        if out and not self._out and drone.stage in ("pilot", "return"):
            self.breaches += 1
            drone._run.event(t, "geofence_breach", policy=self.name, x=float(x), y=float(y),
                             z=float(z), action=self.action,
                             why="above the ceiling" if high else "leaving the fence")
            {"warn": lambda: None, "hold": drone.hold, "return_home": drone.return_home,
             "land": drone.land}[self.action]()
        self._out = out

    def kpis(self, run) -> dict:
        out = super().kpis(run)
        out["geofence_breaches"] = float(self.breaches)
        return out

    def to_dict(self) -> dict:
        return {**super().to_dict(), "polygon": self.polygon, "ceiling_m": self.ceiling_m,
                "action": self.action}


_kpis.register("geofence_breaches", "count", "lower",
               "times the drone would have left the geofence (fa.policy.Geofence)")

__all__ = ["ACTIONS", "Geofence", "inside", "refusal", "world_box"]
