"""The MAVLink side of the simulated autopilot: one UDP socket, messages packed and
parsed by pymavlink (MAVLink 2, the common dialect), and a thread on the wall clock.

The thread receives everything the app sends and answers, on the wall clock as an
autopilot does: heartbeats (1 Hz), the parameter protocol (integer parameters byte-wise in
the float field, as PX4 and MAVSDK encode them), the mission protocol of the mission and the
geofence (``mission_protocol``). Commands and setpoints go to the
simulation (``inbox``), which acts on them at its next step and acknowledges them.
Before the flight starts and after it ended the thread answers commands itself and
keeps streaming the last state, so an app that waits for "landed" or "disarmed"
still sees them. It records what the app last sent and asked for: a hung app's failure
names it (``diagnosis``). Each message carries the next sequence number (``_pack``);
telemetry is built and packed when its burst is sent (``queue_telemetry``).
"""

from __future__ import annotations

import math
import queue
import socket
import struct
import threading
import time

from pymavlink.dialects.v20 import common as M

from . import streams
from .mission_protocol import Plans, name_of

#: PX4 parameters served and applied (defaults of PX4's parameter reference; the climb and
#: descent speeds are replaced by the mission's): name -> value
PARAMS = {"MIS_TAKEOFF_ALT": 2.5, "MPC_XY_CRUISE": 5.0, "MPC_LAND_SPEED": 0.7,
          "MPC_TKO_SPEED": 1.5, "GF_ACTION": 2, "GF_MAX_HOR_DIST": 0.0, "GF_MAX_VER_DIST": 0.0}

#: integer parameters and the values allowed (PX4's GF_ACTION: 0 none, 1 warning, 2 hold, 3
#: return, 4 terminate, 5 land)
INT_PARAMS = {"GF_ACTION": range(6)}

#: inputs PX4 flies that this front-end does not: each kind is named once, in the flight's
#: events (``app_not_emulated``), in ``commands_unsupported`` and in a hang's diagnosis
NOT_FLOWN = {"SET_ATTITUDE_TARGET": "attitude setpoints",
             "SET_ACTUATOR_CONTROL_TARGET": "actuator controls",
             "MANUAL_CONTROL": "manual control (sticks)", "RC_CHANNELS_OVERRIDE": "RC overrides"}

#: bytes: the largest datagram of queued telemetry (within an Ethernet MTU of 1500;
#: MAVSDK's UDP connection reads datagrams of up to 2048 bytes)
MAX_DATAGRAM = 1400

class Link(Plans):
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
        self.fence: list = []               # the geofence's items (``mission_protocol``, ``boundary``)
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
        names, v = list(self.params), self.params[name]
        wire, kind = ((_as_float(int(v)), M.MAV_PARAM_TYPE_INT32) if name in INT_PARAMS
                      else (float(v), M.MAV_PARAM_TYPE_REAL32))
        self.send(M.MAVLink_param_value_message(name.encode(), wire, kind, len(names),
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
            if pid in INT_PARAMS:
                v = _int_of(msg.param_value, INT_PARAMS[pid])
                if v is not None:
                    self.params[pid] = v
                self._param_value(pid)
            elif pid in self.params:
                self.params[pid] = float(msg.param_value)
                if pid == "MPC_XY_CRUISE" and msg.param_value > 0:
                    self.ap.cruise = float(msg.param_value)
                self._param_value(pid)
            else:
                self.asked_missing.add(f"parameter {pid}")

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


def _as_float(v: int) -> float:
    """An integer parameter in PARAM_VALUE's float field, byte-wise (PX4's encoding)."""
    return struct.unpack("<f", struct.pack("<i", v))[0]


def _int_of(value: float, allowed) -> int | None:
    """The integer a PARAM_SET carries: byte-wise (PX4, MAVSDK, QGroundControl) or, from a
    client that sends the number itself, the float's value; None when neither is allowed."""
    for v in (struct.unpack("<i", struct.pack("<f", value))[0], value):
        if math.isfinite(v) and v == int(v) and int(v) in allowed:
            return int(v)
    return None
