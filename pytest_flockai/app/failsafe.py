"""What the simulated autopilot does about the geofence (``boundary``), as PX4 does (a mixin
of ``Autopilot``):

- in flight, at every step (``_geofence``): on leaving the fence, an ``app_geofence_breach``
  event, a STATUSTEXT to the app and GF_ACTION's failsafe: hold, return or land; 0 and 1
  only report it; 4, flight termination, is not emulated (the drone holds). A breach while
  returning or landing is reported and not acted on; the next one counts after the drone
  is back inside;
- a reposition (DO_REPOSITION, MAVSDK's ``goto_location``) to a point outside the fence
  (``outside_fence``): PX4's navigator keeps the drone where it is and logs "Reposition is
  outside geofence", while its commander has already acknowledged the command (ACCEPTED):
  here an ``app_reposition_refused`` event, that STATUSTEXT, and the drone holds.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from pymavlink.dialects.v20 import common as M

from .boundary import ACTIONS, Boundary

NONE = (0.0,) * 7


class Failsafe:
    """The geofence's checks (module docstring)."""

    # provided by Autopilot
    link: Any
    st: Any
    geo: Any
    run: Any
    mode: str
    boundary: Boundary
    _fence_items: list | None   # the link's fence the boundary was built from (None: not yet)
    _gf_out: bool
    gf_breaches: int
    hold: Callable[[float], None]
    c_hold: Callable[..., int]
    c_rtl: Callable[..., int]
    c_land: Callable[..., int]
    not_emulated: Callable[..., None]

    def _fence_why(self, x: float, y: float, z: float) -> str | None:
        """Why (x, y, z) is outside the geofence; None inside, or with no geofence."""
        link = self.link
        if link.fence is not self._fence_items:     # the first check, or a new fence since
            self._fence_items, self.boundary = link.fence, Boundary(link.fence, self.geo)
        p = link.params
        if not self.boundary.shapes and p["GF_MAX_HOR_DIST"] <= 0 and p["GF_MAX_VER_DIST"] <= 0:
            return None                     # no geofence: nothing to check
        return self.boundary.breach(x, y, z, p["GF_MAX_HOR_DIST"], p["GF_MAX_VER_DIST"])

    def _tell(self, text: str) -> None:
        self.link.send(M.MAVLink_statustext_message(M.MAV_SEVERITY_CRITICAL, text.encode()))

    def _geofence(self, t: float) -> None:
        q = self.st.qc
        why = self._fence_why(q[0], q[1], q[2])
        was, self._gf_out = self._gf_out, why is not None
        if why is None or was:
            return
        action = ACTIONS[int(self.link.params["GF_ACTION"])]
        acted = self.mode not in ("RTL", "LAND")      # already returning or landing: reported
        self.gf_breaches += 1
        self.run.event(t, "app_geofence_breach", reason=why, action=action, acted=acted,
                       x=float(q[0]), y=float(q[1]), z=float(q[2]))
        self._tell(f"Geofence violation: {action}")
        if not acted:
            return
        if action == "terminate":
            self.not_emulated("GF_ACTION", "", "flight termination (GF_ACTION 4) is not "
                              "emulated: the drone holds instead")
        if action in ("hold", "terminate"):
            self.c_hold(t, NONE, 0)
        elif action == "return":
            self.c_rtl(t, NONE, 0)
        elif action == "land":
            self.c_land(t, NONE, 0)

    def outside_fence(self, t: float, pos) -> bool:
        """Whether a reposition to ``pos`` (world) is refused by the geofence; if so, the
        drone holds where it is (module docstring)."""
        why = self._fence_why(*pos)
        if why is None:
            return False
        self.run.event(t, "app_reposition_refused", reason=f"the target is {why}",
                       x=float(pos[0]), y=float(pos[1]), z=float(pos[2]))
        self._tell("Reposition is outside geofence")
        self.hold(t)
        return True


__all__ = ["Failsafe"]
