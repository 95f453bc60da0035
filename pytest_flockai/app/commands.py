"""The commands of the simulated autopilot (a mixin of ``Autopilot``): each MAVLink command
the app sends, what it does and its COMMAND_ACK (PX4's behaviour where emulated, else
UNSUPPORTED), the offboard setpoints, and the mission executor (waypoints at the cruise
speed, speed changes, delays, RTL, land; MISSION_CURRENT and MISSION_ITEM_REACHED)."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from ..control.pilots import Waypoints
from ..control.stages import DONE, TAKEOFF
from ..control.stages import LANDING as LAND
from . import frames
from .mavlink_udp import M, name_of
from .pilots import ORBIT_YAW, AppOrbit, Leg, Setpoint
from .streams import RATES

A, DENIED, UNSUP = M.MAV_RESULT_ACCEPTED, M.MAV_RESULT_DENIED, M.MAV_RESULT_UNSUPPORTED
GLOBAL_FRAMES = (M.MAV_FRAME_GLOBAL, M.MAV_FRAME_GLOBAL_INT)
RELATIVE_FRAMES = (M.MAV_FRAME_GLOBAL_RELATIVE_ALT, M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT)


def _ok(v) -> bool:
    return v is not None and math.isfinite(v)


class Commands:
    """Mixin of ``Autopilot`` (which provides the flight state and ``link``)."""

    # provided by Autopilot (the flight's state, the link, the flying helpers)
    st: Any
    stages: Any
    link: Any
    run: Any
    geo: Any
    armed: bool
    mode: str
    cruise: float
    setpoint: Any
    sp_pilot: Any
    mission_active: bool
    mi: int
    leg: Any
    t_last: float
    wall: float
    commands: int
    denied: int
    unsupported: int
    rates: dict
    _due: dict
    _next_tel: float
    _hold_s: float
    _reset_asked: bool
    hold: Callable[[float], None]
    fly: Callable[[float, Any], None]
    goto: Callable[..., int]
    snapshot: Callable[[float], dict]
    _yaw: Callable[[], float]
    _in_reach: Callable[[Any], None]

    @property
    def in_air(self) -> bool:               # pragma: no cover - Autopilot's
        raise NotImplementedError

    #: commands that ask for messages or information (answered, never counted as the app's
    #: commands; what is not served is named in a hang's diagnosis)
    requests = {M.MAV_CMD_SET_MESSAGE_INTERVAL, M.MAV_CMD_REQUEST_MESSAGE,
                M.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, M.MAV_CMD_GET_HOME_POSITION,
                M.MAV_CMD_REQUEST_PROTOCOL_VERSION, M.MAV_CMD_GET_MESSAGE_INTERVAL,
                M.MAV_CMD_REQUEST_CAMERA_INFORMATION, M.MAV_CMD_REQUEST_CAMERA_SETTINGS,
                M.MAV_CMD_REQUEST_STORAGE_INFORMATION, M.MAV_CMD_REQUEST_CAMERA_CAPTURE_STATUS,
                M.MAV_CMD_REQUEST_FLIGHT_INFORMATION}

    # -- dispatch ---------------------------------------------------------------------------
    def handle(self, t: float, msg) -> None:
        kind = msg.get_type()
        if kind.startswith("SET_POSITION_TARGET"):
            self.target(t, msg)
            return
        if kind == "MISSION_SET_CURRENT":
            if 0 <= msg.seq < len(self.link.mission):
                self.mi, self.leg = msg.seq, None
            return
        c = msg.command
        if c in self.requests:
            self.link.ack(c, self.request(msg))
            return
        p = [msg.param1, msg.param2, msg.param3, msg.param4]
        if kind == "COMMAND_INT":
            k = 1e-7 if msg.frame in GLOBAL_FRAMES + RELATIVE_FRAMES else 1.0
            big = (msg.x == 0x7FFFFFFF, msg.y == 0x7FFFFFFF)
            p += [math.nan if big[0] else msg.x * k, math.nan if big[1] else msg.y * k, msg.z]
            frame = msg.frame
        else:
            p += [msg.param5, msg.param6, msg.param7]
            frame = M.MAV_FRAME_GLOBAL
        fn = self._handlers().get(c)
        res = UNSUP if fn is None else fn(t, p, frame)
        self.count(c, res)
        self.run.event(t, "app_command", command=name_of(c),
                       result=M.enums["MAV_RESULT"][res].name.replace("MAV_RESULT_", ""))
        self.link.ack(c, res)

    def count(self, c: int, res: int) -> None:
        self.commands += 1
        if res == UNSUP:
            self.unsupported += 1
        elif res != A:
            self.denied += 1

    def _handlers(self) -> dict:
        return {M.MAV_CMD_COMPONENT_ARM_DISARM: self.c_arm, M.MAV_CMD_NAV_TAKEOFF: self.c_takeoff,
                M.MAV_CMD_NAV_LAND: self.c_land, M.MAV_CMD_NAV_RETURN_TO_LAUNCH: self.c_rtl,
                M.MAV_CMD_DO_SET_MODE: self.c_mode, M.MAV_CMD_DO_REPOSITION: self.c_reposition,
                M.MAV_CMD_DO_CHANGE_SPEED: self.c_speed, M.MAV_CMD_DO_ORBIT: self.c_orbit,
                M.MAV_CMD_MISSION_START: self.c_mission_start,
                M.MAV_CMD_NAV_LOITER_UNLIM: self.c_hold}

    def request(self, msg) -> int:
        c, link = msg.command, self.link
        if c in (M.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES,):
            link.autopilot_version()
            return A
        if c == M.MAV_CMD_GET_HOME_POSITION:
            link.stream("HOME_POSITION", self.snapshot(self.t_last))
            return A
        if c in (M.MAV_CMD_REQUEST_MESSAGE, M.MAV_CMD_SET_MESSAGE_INTERVAL):
            cls = M.mavlink_map.get(int(msg.param1))
            name = cls.msgname if cls is not None else str(int(msg.param1))
            if c == M.MAV_CMD_REQUEST_MESSAGE and name == "AUTOPILOT_VERSION":
                link.autopilot_version()
                return A
            if name not in self.rates:
                link.asked_missing.add(f"message {name}")
                return UNSUP
            if c == M.MAV_CMD_REQUEST_MESSAGE:
                link.stream(name, self.snapshot(self.t_last))
            else:
                us = msg.param2
                self.rates[name] = 0.0 if us < 0 else RATES[name] if us == 0 else min(25.0, 1e6 / us)
                self._due[name] = self._next_tel = self.t_last
            return A
        link.asked_missing.add(f"command {name_of(c)}")
        return UNSUP

    # -- commands -----------------------------------------------------------------------------
    def c_arm(self, t, p, frame) -> int:
        if p[0] >= 0.5:
            if self.st.stage == DONE:
                return DENIED
            self.armed = True
            return A
        if self.in_air:
            return DENIED                   # PX4 refuses to disarm in the air
        self.armed = False
        return A

    def c_takeoff(self, t, p, frame) -> int:
        if not self.stages.grounded or not self.armed:
            return DENIED
        alt = p[6] - self.geo.amsl0 if _ok(p[6]) else self.link.params["MIS_TAKEOFF_ALT"]
        if alt < 0.5:
            return DENIED
        self.stages.climb_speed = self.link.params["MPC_TKO_SPEED"]
        self.stages.take_off(t, self.st.home[2] + alt)
        self.mode = "TAKEOFF"
        return A

    def c_land(self, t, p, frame) -> int:
        if not self.in_air or self.st.stage == LAND:
            return DENIED if not self.in_air else A
        self.mission_active = False
        self.stages.descent_speed = self.link.params["MPC_LAND_SPEED"]
        q, sp = self.st.qc, self.st.sp
        sp[0], sp[1] = q[0], q[1]           # land where the drone is, as PX4 does
        self.stages.land_here(t)
        self.mode = "LAND"
        return A

    def c_rtl(self, t, p, frame) -> int:
        if not self.in_air or self.st.stage == LAND:
            return DENIED
        self.mission_active = False
        self.stages.descent_speed = self.link.params["MPC_LAND_SPEED"]
        self.stages.go_home(t)
        self.mode = "RTL"
        return A

    def c_hold(self, t, p, frame) -> int:
        self.mission_active = False
        self.mode = "HOLD"
        if self.in_air and self.st.stage not in (LAND,):
            self.hold(t)
        return A

    def c_mode(self, t, p, frame) -> int:
        name = frames.mode_name(p[1], p[2])
        if name == "HOLD":
            return self.c_hold(t, p, frame)
        if name == "RTL":
            return self.c_rtl(t, p, frame)
        if name == "LAND":
            return self.c_land(t, p, frame)
        if name == "TAKEOFF":
            return self.c_takeoff(t, [math.nan] * 7, frame)
        if name == "MISSION":
            return self.c_mission_start(t, p, frame)
        if name == "OFFBOARD":
            return self.offboard(t)
        return UNSUP                        # manual, altitude, position control: no sticks

    def c_reposition(self, t, p, frame) -> int:
        if not self.in_air or self.st.stage == LAND:
            return DENIED
        q = self.st.qc
        here = self.geo.to_global(q[0], q[1], q[2])
        lat = p[4] if _ok(p[4]) and p[4] != 0 else here[0]
        lon = p[5] if _ok(p[5]) and p[5] != 0 else here[1]
        rel = here[3] if not _ok(p[6]) else p[6] if frame in RELATIVE_FRAMES else p[6] - self.geo.amsl0
        yaw = frames.yaw_enu(math.radians(p[3])) if _ok(p[3]) else None
        self.mission_active = False
        self.mode = "HOLD"
        return self.goto(t, self.geo.to_world(lat, lon, rel), yaw, p[0] if p[0] > 0 else None)

    def c_speed(self, t, p, frame) -> int:
        if _ok(p[1]) and p[1] > 0:
            self.cruise = float(p[1])
            if self.sp_pilot is not None:
                self.sp_pilot.speed = self.cruise
        return A

    def c_orbit(self, t, p, frame) -> int:
        if not self.in_air or self.st.stage == LAND:
            return DENIED
        q = self.st.qc
        here = self.geo.to_global(q[0], q[1], q[2])
        lat = p[4] if _ok(p[4]) else here[0]
        lon = p[5] if _ok(p[5]) else here[1]
        rel = here[3] if not _ok(p[6]) else p[6] - self.geo.amsl0     # MSL, whatever the frame
        c = self.geo.to_world(lat, lon, rel)
        radius = p[0] if _ok(p[0]) and p[0] != 0 else 10.0     # > 0: clockwise
        speed = abs(p[1]) if _ok(p[1]) and p[1] != 0 else 3.0
        yaw_mode = int(p[2]) if _ok(p[2]) else 0            # 5: unchanged, the orbit's own
        yaw_mode = getattr(self.stages.pilot, "yaw_mode", 0) if yaw_mode == 5 else yaw_mode
        if yaw_mode not in ORBIT_YAW:
            return UNSUP                    # RC-controlled yaw: no sticks
        try:
            self._in_reach(c)
            pilot = AppOrbit((c[0], c[1]), radius, c[2], speed, yaw_mode, self._yaw())
        except Exception as exc:            # ConfigError: out of reach, too fast
            self.run.event(t, "app_refused", reason=str(exc))
            return DENIED
        self.mission_active, self.mode = False, "ORBIT"
        self.fly(t, pilot)
        return A

    # -- offboard ------------------------------------------------------------------------------
    def target(self, t, msg) -> None:
        """A SET_POSITION_TARGET_* setpoint: stored, flown while in OFFBOARD."""
        m, g = msg.type_mask, self.geo
        pos = vel = None
        yaw = None if m & M.POSITION_TARGET_TYPEMASK_YAW_IGNORE else frames.yaw_enu(msg.yaw)
        rate = None if yaw is not None or m & M.POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE \
            else -float(msg.yaw_rate)       # NED's clockwise yaw rate, where no yaw is given
        if msg.get_type() == "SET_POSITION_TARGET_LOCAL_NED":
            if msg.coordinate_frame not in (M.MAV_FRAME_LOCAL_NED, M.MAV_FRAME_BODY_NED):
                self.link.asked_missing.add(f"setpoint frame {msg.coordinate_frame}")
                return
            if not m & M.POSITION_TARGET_TYPEMASK_X_IGNORE:
                pos = g.ned_to_world(msg.x, msg.y, msg.z)
            if not m & M.POSITION_TARGET_TYPEMASK_VX_IGNORE:
                vel = (msg.vy, msg.vx, -msg.vz)
                if msg.coordinate_frame == M.MAV_FRAME_BODY_NED:   # forward/right/down
                    h = self._yaw()
                    vel = (msg.vx * math.cos(h) + msg.vy * math.sin(h),
                           msg.vx * math.sin(h) - msg.vy * math.cos(h), -msg.vz)
        else:
            if not m & M.POSITION_TARGET_TYPEMASK_X_IGNORE:
                rel = msg.alt if msg.coordinate_frame in RELATIVE_FRAMES else msg.alt - g.amsl0
                pos = g.to_world(msg.lat_int * 1e-7, msg.lon_int * 1e-7, rel)
            if not m & M.POSITION_TARGET_TYPEMASK_VX_IGNORE:
                vel = (msg.vy, msg.vx, -msg.vz)
        self.setpoint = (pos, vel, yaw, self.wall, rate)
        if self.mode == "OFFBOARD" and self.sp_pilot is not None:
            self.sp_pilot.set(pos, vel, yaw, yaw_rate=rate)

    def offboard(self, t) -> int:
        """Enter OFFBOARD: PX4 refuses it without a recent setpoint; on the pad, armed,
        the setpoints fly the take-off."""
        if self.setpoint is None or self.wall - self.setpoint[3] > 1.0:
            return DENIED
        if self.st.stage in (DONE, LAND) or (self.stages.grounded and not self.armed):
            return DENIED
        if self.stages.grounded:
            self.stages.take_off(t, self.st.home[2] + 0.1)
        pos, vel, yaw, _, rate = self.setpoint
        q = self.st.qc
        sp = Setpoint(q[2], self.cruise, pos=pos, vel=vel, yaw=self._yaw() if yaw is None else yaw,
                      yaw_rate=rate)
        self.mission_active = False
        self.fly(t, sp)
        self.sp_pilot = sp
        self.mode = "OFFBOARD"
        return A

    # -- missions ------------------------------------------------------------------------------
    def mission_reset(self) -> None:
        self.mission_active = False
        self.mi = 0
        self.leg = None
        self._reset_asked = False

    def c_mission_start(self, t, p, frame) -> int:
        items = self.link.mission
        if not items or not self.armed or self.st.stage in (DONE, LAND):
            return DENIED
        if self._reset_asked:
            self.mission_reset()
        if self.stages.grounded:
            self.stages.take_off(t, self.st.home[2] + self.link.params["MIS_TAKEOFF_ALT"])
        self.mission_active, self.leg = True, None
        self.mode = "MISSION"
        return A

    def mission_step(self, t: float) -> None:
        if self._reset_asked:
            self.mission_reset()
            return
        stage = self.st.stage
        if self.stages.grounded or stage == TAKEOFF or stage >= 2:   # climbing, returning
            return
        items = self.link.mission
        if self.leg is None:
            if self.mi >= len(items):
                self.mission_active = False
                self.mode = "HOLD"
                self.hold(t)
                return
            self._begin(t, items[self.mi])
            return
        leg, until = self.leg
        if isinstance(leg, Leg) and not leg.done:
            return
        if until is None:
            self.leg = (None, t + self._hold_s)
            return
        if t >= until:
            self._reached(t)

    def _reached(self, t: float) -> None:
        self.link.send(M.MAVLink_mission_item_reached_message(self.mi))
        self.mi += 1
        self.leg = None
        if self.mi < len(self.link.mission):
            self.link.stream("MISSION_CURRENT", self.snapshot(t))

    def _begin(self, t: float, it: dict) -> None:
        c = it["command"]
        self.link.stream("MISSION_CURRENT", self.snapshot(t))
        self._hold_s = 0.0
        if c in (M.MAV_CMD_NAV_WAYPOINT, M.MAV_CMD_NAV_TAKEOFF, M.MAV_CMD_NAV_LOITER_TIME):
            q = self.st.qc
            here = self.geo.to_global(q[0], q[1], q[2])
            lat = it["x"] if it["x"] else here[0]
            lon = it["y"] if it["y"] else here[1]
            rel = it["z"] - self.geo.amsl0 if it["frame"] in GLOBAL_FRAMES else it["z"]
            pt = self.geo.to_world(lat, lon, rel)
            yaw = (frames.yaw_enu(math.radians(it["p"][3])) if _ok(it["p"][3])
                   else math.atan2(pt[1] - q[1], pt[0] - q[0]) if math.dist(pt[:2], q[:2]) > 1.0
                   else self._yaw())
            if c != M.MAV_CMD_NAV_TAKEOFF:
                self._hold_s = max(0.0, it["p"][0] or 0.0)
            try:
                self._in_reach(pt)
                leg = Leg(Waypoints([pt], self.cruise, yaw=yaw))
            except Exception as exc:        # ConfigError: out of reach
                self.run.event(t, "app_refused", reason=f"mission item {self.mi}: {exc}")
                self.mission_active = False
                self.mode = "HOLD"
                self.hold(t)
                return
            self.fly(t, leg)
            self.leg = (leg, None)
        elif c == M.MAV_CMD_DO_CHANGE_SPEED:
            self.c_speed(t, it["p"], it["frame"])
            self._reached(t)
        elif c in (M.MAV_CMD_NAV_DELAY, M.MAV_CMD_NAV_LOITER_UNLIM):
            self.hold(t)
            wait = math.inf if c == M.MAV_CMD_NAV_LOITER_UNLIM else max(0.0, it["p"][0])
            self.leg = (None, t + wait)
        elif c == M.MAV_CMD_NAV_RETURN_TO_LAUNCH:
            self._reached(t)
            self.c_rtl(t, it["p"], it["frame"])
        elif c == M.MAV_CMD_NAV_LAND:
            self._reached(t)
            self.c_land(t, it["p"], it["frame"])
        else:                               # gimbal, camera: nothing to point or trigger
            self._reached(t)
