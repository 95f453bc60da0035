"""The mission protocol of the simulated autopilot (a mixin of ``mavlink_udp.Link``): upload,
download and clear of the two plans PX4 keeps for an app, the mission
(MAV_MISSION_TYPE_MISSION) and the geofence (MAV_MISSION_TYPE_FENCE: inclusion and exclusion
polygons and circles, checked in flight by ``boundary``). Rally points are refused
(MAV_MISSION_UNSUPPORTED), and named in the flight's events. A mission item the drone cannot
fly is refused with MAV_MISSION_UNSUPPORTED (or _UNSUPPORTED_FRAME), a geofence that is not
one (a polygon of fewer than 3 vertices, a circle without a radius) with MAV_MISSION_INVALID;
either is named in an event (``app_mission_refused``) and in ``app.commands_unsupported``.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

from pymavlink.dialects.v20 import common as M

from . import boundary

#: mission items the drone flies (the rest are refused at upload)
MISSION_FLOWN = {M.MAV_CMD_NAV_WAYPOINT, M.MAV_CMD_NAV_TAKEOFF, M.MAV_CMD_NAV_LAND,
                 M.MAV_CMD_NAV_RETURN_TO_LAUNCH, M.MAV_CMD_NAV_LOITER_TIME,
                 M.MAV_CMD_NAV_LOITER_UNLIM, M.MAV_CMD_NAV_DELAY, M.MAV_CMD_DO_CHANGE_SPEED}
#: mission items accepted and skipped: there is no gimbal or camera to point or trigger
MISSION_SKIPPED = {M.MAV_CMD_DO_MOUNT_CONTROL, M.MAV_CMD_DO_GIMBAL_MANAGER_PITCHYAW,
                   M.MAV_CMD_IMAGE_START_CAPTURE, M.MAV_CMD_IMAGE_STOP_CAPTURE,
                   M.MAV_CMD_VIDEO_START_CAPTURE, M.MAV_CMD_VIDEO_STOP_CAPTURE,
                   M.MAV_CMD_DO_SET_CAM_TRIGG_DIST, M.MAV_CMD_DO_SET_ROI_NONE}
MISSION_FRAMES = {M.MAV_FRAME_GLOBAL, M.MAV_FRAME_GLOBAL_RELATIVE_ALT, M.MAV_FRAME_GLOBAL_INT,
                  M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, M.MAV_FRAME_MISSION}
MISSION, FENCE = M.MAV_MISSION_TYPE_MISSION, M.MAV_MISSION_TYPE_FENCE


def name_of(cmd: int) -> str:
    e = M.enums["MAV_CMD"].get(int(cmd))
    return e.name.replace("MAV_CMD_", "") if e is not None else str(cmd)


class Plans:
    """The mission protocol (module docstring) on the link's ``mission`` and ``fence`` (the
    items as stored, ``item_of``; each upload or clear stores a new list)."""

    # provided by Link (the autopilot, the app's address, the plans, the sender)
    ap: Any
    app_id: tuple
    mission: list
    fence: list
    _up: dict | None
    send: Callable[[Any], None]

    def _plan(self, mtype: int) -> list | None:
        return self.mission if mtype == MISSION else self.fence if mtype == FENCE else None

    def _mission_ack(self, result: int, mtype: int = MISSION) -> None:
        self.send(M.MAVLink_mission_ack_message(*self.app_id, result, mtype))

    def _request_next(self) -> None:
        up = self._up
        assert up is not None
        up["resend"] = time.monotonic() + 0.5
        self.send(M.MAVLink_mission_request_int_message(*self.app_id, len(up["items"]),
                                                        up["type"]))

    def _mission(self, kind: str, msg) -> None:
        self.app_id = (msg.get_srcSystem(), msg.get_srcComponent())
        mtype = getattr(msg, "mission_type", MISSION)
        if kind == "MISSION_COUNT":
            if mtype not in (MISSION, FENCE):
                if msg.count:
                    self.ap.not_emulated("MISSION_COUNT", "rally points (MAV_MISSION_TYPE_RALLY)")
                self._mission_ack(M.MAV_MISSION_ACCEPTED if msg.count == 0
                                  else M.MAV_MISSION_UNSUPPORTED, mtype)
                return
            if msg.count == 0:
                self._store(mtype, [])
                self._mission_ack(M.MAV_MISSION_ACCEPTED, mtype)
                return
            self._up = {"count": msg.count, "items": [], "type": mtype}
            self._request_next()
        elif kind in ("MISSION_ITEM_INT", "MISSION_ITEM") and self._up is not None:
            up = self._up
            if msg.seq != len(up["items"]) or mtype != up["type"]:
                return                      # a repeat: the next request goes out again
            refused = self._refuse_item(msg, mtype)
            if refused is None:
                up["items"].append(item_of(msg, kind == "MISSION_ITEM_INT"))
                if len(up["items"]) < up["count"]:
                    self._request_next()
                    return
                refused = self._refuse_fence(up["items"]) if mtype == FENCE else None
                if refused is None:
                    self._store(mtype, up["items"])
            self._up = None
            self._mission_ack(M.MAV_MISSION_ACCEPTED if refused is None else refused, mtype)
        elif kind == "MISSION_REQUEST_LIST":
            self.send(M.MAVLink_mission_count_message(*self.app_id,
                                                      len(self._plan(mtype) or ()), mtype))
        elif kind in ("MISSION_REQUEST_INT", "MISSION_REQUEST"):
            plan = self._plan(mtype) or []
            if 0 <= msg.seq < len(plan):
                it = plan[msg.seq]
                self.send(M.MAVLink_mission_item_int_message(
                    *self.app_id, msg.seq, it["frame"], it["command"], 0, 1, *it["p"],
                    int(round(it["x"] * 1e7)), int(round(it["y"] * 1e7)), it["z"], mtype))
        elif kind == "MISSION_CLEAR_ALL":
            for t in ((MISSION, FENCE) if mtype == M.MAV_MISSION_TYPE_ALL else (mtype,)):
                if t in (MISSION, FENCE):
                    self._store(t, [])
            self._mission_ack(M.MAV_MISSION_ACCEPTED, mtype)

    def _store(self, mtype: int, items: list) -> None:
        if mtype == MISSION:
            self.mission = items
            self.ap.mission_uploaded()
        else:
            self.fence = items

    def _refuse_item(self, msg, mtype: int) -> int | None:
        cmd = msg.command
        if mtype == FENCE:
            if cmd in boundary.ITEMS and msg.frame in MISSION_FRAMES - {M.MAV_FRAME_MISSION}:
                return None
            why = (f"{name_of(cmd)} is not a geofence item (allowed: polygon vertices and "
                   f"circles, inclusion or exclusion, in a global frame)")
            res = M.MAV_MISSION_UNSUPPORTED
        elif cmd in MISSION_SKIPPED:
            return None
        elif cmd not in MISSION_FLOWN:
            why, res = f"{name_of(cmd)} is not flown by the simulated autopilot", \
                M.MAV_MISSION_UNSUPPORTED
        elif msg.frame not in MISSION_FRAMES:
            why, res = (f"{name_of(cmd)} in frame {msg.frame} (allowed: global, relative "
                        f"altitude, mission)"), M.MAV_MISSION_UNSUPPORTED_FRAME
        else:
            return None
        self.ap.refused_item(msg.seq, name_of(cmd), why)
        return res

    def _refuse_fence(self, items: list) -> int | None:
        """MAV_MISSION_INVALID for a geofence that is not one (``boundary.check``)."""
        bad = boundary.check(items)
        if bad is None:
            return None
        seq, why = bad
        self.ap.refused_item(seq, name_of(items[seq]["command"]), why)
        return M.MAV_MISSION_INVALID


def item_of(msg, is_int: bool) -> dict:
    """A plan item as stored: frame, command, params 1-4, x/y in degrees, z in m."""
    k = 1e-7 if is_int else 1.0
    return {"seq": msg.seq, "frame": msg.frame, "command": msg.command,
            "p": [msg.param1, msg.param2, msg.param3, msg.param4],
            "x": msg.x * k, "y": msg.y * k, "z": float(msg.z)}


__all__ = ["FENCE", "MISSION", "MISSION_FLOWN", "MISSION_FRAMES", "MISSION_SKIPPED", "Plans",
           "item_of", "name_of"]
