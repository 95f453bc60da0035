"""The MAVLink side of the simulated autopilot: one UDP socket, messages packed and
parsed by pymavlink (MAVLink 2, the common dialect), and a thread on the wall clock.

The thread receives everything the app sends and answers, on the wall clock as an
autopilot does: heartbeats (1 Hz), the parameter protocol, the mission protocol
(upload, download, clear; an item the drone cannot fly is refused with
MAV_MISSION_UNSUPPORTED and named in an event). Commands and setpoints go to the
simulation (``inbox``), which acts on them at its next step and acknowledges them.
Before the flight starts and after it ended the thread answers commands itself and
keeps streaming the last state, so an app that waits for "landed" or "disarmed"
still sees them. It records what the app last sent and asked for: a hung app's failure
names it (``diagnosis``). Each message carries the next sequence number (``_pack``);
telemetry is built and packed when its burst is sent (``queue_telemetry``).
"""

from __future__ import annotations

import queue
import socket
import threading
import time

from pymavlink.dialects.v20 import common as M

from . import streams

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
#: PX4 parameters served and applied (defaults of PX4's parameter reference; the climb and
#: descent speeds are replaced by the mission's): name -> value
PARAMS = {"MIS_TAKEOFF_ALT": 2.5, "MPC_XY_CRUISE": 5.0, "MPC_LAND_SPEED": 0.7,
          "MPC_TKO_SPEED": 1.5}

#: inputs PX4 flies that this front-end does not: each kind is named once, in the flight's
#: events (``app_not_emulated``), in ``commands_unsupported`` and in a hang's diagnosis
NOT_FLOWN = {"SET_ATTITUDE_TARGET": "attitude setpoints",
             "SET_ACTUATOR_CONTROL_TARGET": "actuator controls",
             "MANUAL_CONTROL": "manual control (sticks)", "RC_CHANNELS_OVERRIDE": "RC overrides"}

#: bytes: the largest datagram of queued telemetry (within an Ethernet MTU of 1500;
#: MAVSDK's UDP connection reads datagrams of up to 2048 bytes)
MAX_DATAGRAM = 1400

def name_of(cmd: int) -> str:
    e = M.enums["MAV_CMD"].get(int(cmd))
    return e.name.replace("MAV_CMD_", "") if e is not None else str(cmd)


class Link:
    """The autopilot's UDP link to the app at 127.0.0.1:``port`` (see the module
    docstring). ``ap``: the ``Autopilot`` whose state it reports."""

    def __init__(self, port: int, ap):
        self.port, self.ap = int(port), ap
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.settimeout(0.05)
        self.mav = M.MAVLink(None, srcSystem=1, srcComponent=1)
        self.mav.robust_parsing = True
        self._lock = threading.Lock()
        #: what is not sent yet, in order (``queue``, ``queue_telemetry``): messages, and
        #: (telemetry names, state) pairs built into messages when they are sent
        self._out: list = []
        self.queued_at = 0.0                # time.monotonic() of the oldest of them
        self.inbox: queue.SimpleQueue = queue.SimpleQueue()
        self.params = dict(PARAMS)
        self.mission: list = []
        self._up: dict | None = None        # an upload in progress: {"count", "items", "type"}
        self.app_id = (255, 0)
        self.last_msg: tuple | None = None  # (name, wall time) of the app's last message
        self.last_cmd: tuple | None = None  # (command name, result name)
        self.asked_missing: set = set()     # messages the app asked for that are not sent
        self.seen = 0
        self.sim_running = False
        self.snap: dict | None = None       # the last state, streamed outside the flight
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._serve, name="flockai-mavlink", daemon=True)

    def send(self, msg) -> None:
        """Send ``msg`` now, after the telemetry queued before it (one datagram)."""
        with self._lock:
            self._out.append(msg)
            self._flush()

    def queue(self, msgs) -> None:
        """Queue ``msgs`` for the next datagram (``flush``): telemetry of one burst of
        simulated steps reaches the app at one instant however it is sent."""
        with self._lock:
            if not self._out:
                self.queued_at = time.monotonic()
            self._out.extend(msgs)

    def queue_telemetry(self, names, state: dict) -> None:
        """Queue the telemetry messages ``names`` of ``state`` (``Autopilot.snapshot``):
        they are built and packed when the burst is sent (``flush``), one after the other
        with the next sequence numbers, not at each simulated step that queued them."""
        self.queue(((tuple(names), state),))

    def _pack(self, msg) -> bytes:
        """``msg`` packed with the next sequence number (``pack`` does not advance it)."""
        buf = msg.pack(self.mav)
        self.mav.seq = (self.mav.seq + 1) % 256
        self.mav.total_packets_sent += 1
        return buf

    @property
    def pending(self) -> bool:
        """Telemetry is queued and not sent yet."""
        return bool(self._out)

    def flush(self) -> None:
        with self._lock:
            self._flush()

    def _flush(self) -> None:
        """Send what is queued, in order, in datagrams of at most ``MAX_DATAGRAM`` bytes
        (MAVLink parsers read a datagram as a byte stream: one kernel call for many)."""
        items, self._out = self._out, []
        bufs: list = []
        n = 0
        for item in items:
            if isinstance(item, tuple):         # (names, state): build the messages now
                names, state = item
                msgs = [m for m in (self.message(k, state) for k in names) if m is not None]
            else:
                msgs = [item]
            for m in msgs:
                buf = self._pack(m)
                if n + len(buf) > MAX_DATAGRAM and bufs:
                    self._sendto(b"".join(bufs))
                    bufs, n = [], 0
                bufs.append(buf)
                n += len(buf)
        if bufs:
            self._sendto(b"".join(bufs))

    def _sendto(self, buf: bytes) -> None:
        try:
            self.sock.sendto(buf, ("127.0.0.1", self.port))
        except OSError:
            pass                            # the app is not listening (yet): UDP drops it

    def ack(self, command: int, result: int) -> None:
        self.last_cmd = (name_of(command), M.enums["MAV_RESULT"][result].name)
        self.send(M.MAVLink_command_ack_message(command, result, 0, 0, *self.app_id))

    def heartbeat(self) -> None:
        ap = self.ap
        base = M.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | (M.MAV_MODE_FLAG_SAFETY_ARMED if ap.armed else 0)
        status = M.MAV_STATE_ACTIVE if ap.in_air else M.MAV_STATE_STANDBY
        self.send(M.MAVLink_heartbeat_message(M.MAV_TYPE_QUADROTOR, M.MAV_AUTOPILOT_PX4, base,
                                              ap.custom_mode, status, 3))

    def stream(self, name: str, s: dict) -> None:
        """Send telemetry message ``name`` from the state ``s`` (``Autopilot.snapshot``)."""
        m = self.message(name, s)
        if m is not None:
            self.send(m)

    def message(self, name: str, s: dict):
        """Telemetry message ``name`` from the state ``s`` (None: not one streamed)."""
        return streams.message(name, s, len(self.mission))

    def autopilot_version(self) -> None:
        caps = (M.MAV_PROTOCOL_CAPABILITY_MISSION_INT | M.MAV_PROTOCOL_CAPABILITY_COMMAND_INT
                | M.MAV_PROTOCOL_CAPABILITY_PARAM_FLOAT | M.MAV_PROTOCOL_CAPABILITY_MAVLINK2
                | M.MAV_PROTOCOL_CAPABILITY_SET_POSITION_TARGET_LOCAL_NED
                | M.MAV_PROTOCOL_CAPABILITY_SET_POSITION_TARGET_GLOBAL_INT)
        self.send(M.MAVLink_autopilot_version_message(caps, 0, 0, 0, 0, [0] * 8, [0] * 8,
                                                      [0] * 8, 0, 0, 1))

    # -- the wall-clock thread ---------------------------------------------------------
    def start(self) -> None:
        self._thread.start()

    def wake(self) -> None:
        """Wake the thread from its wait (an empty datagram to its own socket): the
        flight ended (stream the last state from now) or the link closes."""
        try:
            self.sock.sendto(b"", self.sock.getsockname())
        except OSError:
            pass

    def close(self) -> None:
        self._stop.set()
        self.wake()
        if self._thread.is_alive():
            self._thread.join(timeout=2.0)
        self.sock.close()

    def _serve(self) -> None:
        next_hb = next_tel = 0.0
        while not self._stop.is_set():
            now = time.monotonic()
            if now >= next_hb:
                self.heartbeat()
                next_hb = now + 1.0
            if not self.sim_running and self.snap is not None and now >= next_tel:
                self.queue_telemetry((
                    "GLOBAL_POSITION_INT", "LOCAL_POSITION_NED", "ATTITUDE", "SYS_STATUS",
                    "EXTENDED_SYS_STATE", "BATTERY_STATUS", "GPS_RAW_INT", "HOME_POSITION"),
                    self.snap)
                self.flush()
                next_tel = now + 0.25
            wake = next_hb
            if self._up is not None:
                if now >= self._up["resend"]:
                    self._request_next()
                wake = min(wake, self._up["resend"])
            if not self.sim_running and self.snap is not None:
                wake = min(wake, next_tel)
            self.sock.settimeout(max(0.005, wake - now))   # wakes for what is due only
            try:
                data = self.sock.recv(65535)
            except TimeoutError:
                continue
            except OSError:
                return
            if not data:                    # ``wake``: the flight ended or the link closes
                continue
            try:
                msgs = self.mav.parse_buffer(data) or []
            except Exception:               # a malformed datagram: skip it, as PX4 does
                continue
            for msg in msgs:
                self._handle(msg)

    def _handle(self, msg) -> None:
        kind = msg.get_type()
        if kind == "BAD_DATA":
            return
        self.seen += 1
        self.last_msg = (kind, time.monotonic())
        if kind == "HEARTBEAT":
            self.app_id = (msg.get_srcSystem(), msg.get_srcComponent())
            return
        tgt = (getattr(msg, "target_system", 1), getattr(msg, "target_component", 1))
        if tgt[0] not in (0, 1) or (tgt[1] not in (0, 1) and kind.startswith("COMMAND")):
            return                          # for another system or component (a camera...)
        if kind in ("COMMAND_LONG", "COMMAND_INT", "SET_POSITION_TARGET_LOCAL_NED",
                    "SET_POSITION_TARGET_GLOBAL_INT", "MISSION_SET_CURRENT"):
            self.app_id = (msg.get_srcSystem(), msg.get_srcComponent())
            if self.sim_running:
                self.inbox.put((time.monotonic(), msg))     # acted on by its arrival
            else:
                self.ap.off_flight(msg)
        elif kind in NOT_FLOWN:
            what = f"{kind} ({NOT_FLOWN[kind]} are not flown)"
            if what not in self.asked_missing:
                self.asked_missing.add(what)
                self.ap.not_emulated(kind, NOT_FLOWN[kind])
        elif kind.startswith("PARAM_"):
            self._param(kind, msg)
        elif kind.startswith("MISSION_"):
            self._mission(kind, msg)

    # -- parameters --------------------------------------------------------------------
    def _param_value(self, name: str) -> None:
        names = list(self.params)
        self.send(M.MAVLink_param_value_message(name.encode(), float(self.params[name]),
                                                M.MAV_PARAM_TYPE_REAL32, len(names),
                                                names.index(name)))

    def _param(self, kind: str, msg) -> None:
        names = list(self.params)
        if kind == "PARAM_REQUEST_LIST":
            for n in names:
                self._param_value(n)
            return
        pid = msg.param_id
        pid = pid.decode(errors="replace") if isinstance(pid, bytes) else str(pid)
        pid = pid.rstrip("\x00")
        if kind == "PARAM_REQUEST_READ":
            if 0 <= msg.param_index < len(names) and not pid:
                pid = names[msg.param_index]
            if pid in self.params:
                self._param_value(pid)
            else:
                self.asked_missing.add(f"parameter {pid}")
        elif kind == "PARAM_SET":
            if pid in self.params:
                self.params[pid] = float(msg.param_value)
                if pid == "MPC_XY_CRUISE" and msg.param_value > 0:
                    self.ap.cruise = float(msg.param_value)
                self._param_value(pid)
            else:
                self.asked_missing.add(f"parameter {pid}")

    # -- the mission protocol ----------------------------------------------------------
    def _mission_ack(self, result: int, mtype: int = 0) -> None:
        self.send(M.MAVLink_mission_ack_message(*self.app_id, result, mtype))

    def _request_next(self) -> None:
        up = self._up
        assert up is not None
        up["resend"] = time.monotonic() + 0.5
        self.send(M.MAVLink_mission_request_int_message(*self.app_id, len(up["items"]),
                                                        up["type"]))

    def _mission(self, kind: str, msg) -> None:
        self.app_id = (msg.get_srcSystem(), msg.get_srcComponent())
        mtype = getattr(msg, "mission_type", 0)
        if kind == "MISSION_COUNT":
            if mtype != M.MAV_MISSION_TYPE_MISSION:
                self._mission_ack(M.MAV_MISSION_ACCEPTED if msg.count == 0
                                  else M.MAV_MISSION_UNSUPPORTED, mtype)
                return
            if msg.count == 0:
                self.mission = []
                self._mission_ack(M.MAV_MISSION_ACCEPTED)
                return
            self._up = {"count": msg.count, "items": [], "type": mtype}
            self._request_next()
        elif kind in ("MISSION_ITEM_INT", "MISSION_ITEM") and self._up is not None:
            up = self._up
            if msg.seq != len(up["items"]):
                return                      # a repeat: the next request goes out again
            refused = self._refuse_item(msg)
            if refused is not None:
                self._up = None
                self._mission_ack(refused)
                return
            up["items"].append(item_of(msg, kind == "MISSION_ITEM_INT"))
            if len(up["items"]) == up["count"]:
                self._up = None
                self.mission = up["items"]
                self.ap.mission_uploaded()
                self._mission_ack(M.MAV_MISSION_ACCEPTED)
            else:
                self._request_next()
        elif kind == "MISSION_REQUEST_LIST":
            n = len(self.mission) if mtype == M.MAV_MISSION_TYPE_MISSION else 0
            self.send(M.MAVLink_mission_count_message(*self.app_id, n, mtype))
        elif kind in ("MISSION_REQUEST_INT", "MISSION_REQUEST"):
            if 0 <= msg.seq < len(self.mission):
                it = self.mission[msg.seq]
                self.send(M.MAVLink_mission_item_int_message(
                    *self.app_id, msg.seq, it["frame"], it["command"], 0, 1, *it["p"],
                    int(round(it["x"] * 1e7)), int(round(it["y"] * 1e7)), it["z"], mtype))
        elif kind == "MISSION_CLEAR_ALL":
            if mtype in (M.MAV_MISSION_TYPE_MISSION, M.MAV_MISSION_TYPE_ALL):
                self.mission = []
                self.ap.mission_uploaded()
            self._mission_ack(M.MAV_MISSION_ACCEPTED, mtype)

    def _refuse_item(self, msg) -> int | None:
        cmd = msg.command
        if cmd in MISSION_SKIPPED:
            return None
        if cmd not in MISSION_FLOWN:
            why, res = f"{name_of(cmd)} is not flown by the simulated autopilot", \
                M.MAV_MISSION_UNSUPPORTED
        elif msg.frame not in MISSION_FRAMES:
            why, res = (f"{name_of(cmd)} in frame {msg.frame} (allowed: global, relative "
                        f"altitude, mission)"), M.MAV_MISSION_UNSUPPORTED_FRAME
        else:
            return None
        self.ap.refused_item(msg.seq, name_of(cmd), why)
        return res

    # -- diagnosis of a hung app -------------------------------------------------------
    def diagnosis(self) -> str:
        if self.last_msg is None:
            return (f"the app never sent a MAVLink message to the drone (it sends to "
                    f"127.0.0.1:{self.port}; does the app listen there? see "
                    f"FLOCKAI_MAVLINK_URL)")
        name, at = self.last_msg
        out = [f"its last message was {name} {time.monotonic() - at:.1f} s before the end"]
        if self.last_cmd is not None:
            out.append(f"its last command {self.last_cmd[0]} was answered {self.last_cmd[1]}")
        if self.asked_missing:
            out.append("it asked for what is not emulated: " + ", ".join(sorted(self.asked_missing)))
        return "; ".join(out)


def item_of(msg, is_int: bool) -> dict:
    """A mission item as stored: frame, command, params 1-4, x/y in degrees, z in m."""
    k = 1e-7 if is_int else 1.0
    return {"seq": msg.seq, "frame": msg.frame, "command": msg.command,
            "p": [msg.param1, msg.param2, msg.param3, msg.param4],
            "x": msg.x * k, "y": msg.y * k, "z": float(msg.z)}
