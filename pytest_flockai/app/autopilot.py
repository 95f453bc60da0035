"""The simulated PX4-style autopilot: a ``Policy`` that keeps the drone on its pad until
the app commands a take-off, turns the app's MAVLink commands into the stage machine's
and the pilots' actions, streams telemetry from what the drone estimates, and paces
the simulated clock at ``speed`` times the wall clock.

Every 40 ms of simulated time (25 Hz) it acts on the commands the link received
and acknowledges each (COMMAND_ACK: ACCEPTED, DENIED where PX4 refuses, UNSUPPORTED
where nothing is emulated), steps the mission, and sends the telemetry that is due.
What the app sees is on the paced clock (``speed``: simulated seconds per wall second;
falling behind is measured as ``lag``): a step that sends telemetry, or the first step
after a message arrived, is computed at its paced wall time; the steps in between run
late, in one burst (``_pace``), so the simulation wakes at the telemetry's rate, not
at every step. Its per-flight state lives on the bound copy (``Run.policies``), as for
every policy.
"""

from __future__ import annotations

import math
import queue
import time
from collections import deque

from .. import limits
from ..control.stages import DONE, PILOT, RETURN, TAKEOFF
from ..control.stages import LANDING as LAND
from ..control.tracking import yaw_of
from ..errors import ConfigError
from ..policy.base import Policy
from . import frames
from .commands import Commands
from .failsafe import Failsafe
from .mavlink_udp import Link, M
from .pilots import Setpoint
from .streams import RATES

#: s of simulated time between the autopilot's steps (25 Hz: commands, setpoints, telemetry)
PERIOD_S = 0.04
#: s of wall time the simulation may run ahead of the paced clock before it sleeps: each
#: sleep costs a wake-up on cold caches, so at speeds above 1 the steps run in bursts of
#: this length (10 ms of wall time: 0.2 s of simulated time at 20x, one step at 1x)
SLEEP_MIN_S = 0.010
#: s of wall time without a setpoint after which OFFBOARD falls back to HOLD (PX4's
#: COM_OF_LOSS_T default is 1 s)
OFFBOARD_LOSS_S = 1.0


def _floats(a) -> list:
    """``a`` (an array or a sequence) as a list of Python floats."""
    return a.tolist() if hasattr(a, "tolist") else [float(x) for x in a]


class Autopilot(Policy, Commands, Failsafe):
    """The app's autopilot (module docstring); ``port``: the UDP port the app listens
    on; ``speed``: simulated seconds per wall second; ``deadline``: time.monotonic()
    after which the flight stops ("app_timeout")."""

    def __init__(self, port: int, speed: float = 1.0, deadline: float = math.inf):
        super().__init__("app", period_s=PERIOD_S)
        self.port, self.speed, self.deadline = int(port), float(speed), float(deadline)
        self.proc = None                    # the app's Popen, set by the runner

    def to_dict(self) -> dict:
        return {"type": "Autopilot", "name": self.name, "speed": self.speed}

    def start(self, run) -> None:
        self.run, self.st, self.stages = run, run.vehicle, run.stages
        self.stages.wait_on_ground(0.0)
        self.geo = frames.Geo(self.st.home)
        hl = self.geo.to_global(*self.st.home)      # the pad: HOME_POSITION's fields
        self._home_int = (int(round(hl[0] * 1e7)), int(round(hl[1] * 1e7)), int(hl[2] * 1000))
        self.armed, self.mode = False, "READY"
        self.t_last = 0.0
        self.commands = self.denied = self.unsupported = 0
        self.lag_max = 0.0
        self.lag_sum = 0.0
        self.n_steps = 0
        self._w0: float | None = None
        self.wall = 0.0                     # the paced wall time of this step (monotonic s)
        self._pending: deque = deque()      # (arrival, message) not acted on yet
        self._next_poll = 0.0
        self._app_gone = False
        self.rates = dict(RATES)
        self._due = dict.fromkeys(RATES, 0.0)
        self._next_tel = 0.0
        self.cruise = 5.0
        self.setpoint: tuple | None = None   # (pos, vel, yaw, wall time, yaw rate) from the app
        self.sp_pilot: Setpoint | None = None
        self.mission_reset()
        self.link = Link(self.port, self)
        self._fence_items, self._gf_out, self.gf_breaches = None, False, 0   # see Failsafe
        self.link.params["MPC_LAND_SPEED"] = self.stages.descent_speed
        self.link.params["MPC_TKO_SPEED"] = self.stages.climb_speed
        self.link.sim_running = True
        self.link.start()

    # -- what the app sees ---------------------------------------------------------------
    @property
    def custom_mode(self) -> int:
        return frames.custom_mode(self.mode)

    @property
    def in_air(self) -> bool:
        return not self.stages.grounded and self.st.stage != DONE

    def landed_state(self) -> int:
        stage = self.st.stage
        if not self.in_air:
            return M.MAV_LANDED_STATE_ON_GROUND
        if stage == TAKEOFF:
            return M.MAV_LANDED_STATE_TAKEOFF
        if stage == LAND:
            return M.MAV_LANDED_STATE_LANDING
        return M.MAV_LANDED_STATE_IN_AIR

    def snapshot(self, t: float) -> dict:
        """The telemetry fields of this instant, from the drone's navigation state."""
        st, g = self.st, self.geo
        q, v = _floats(st.qc), _floats(st.vc)     # NumPy scalars make the arithmetic slower
        lat, lon, amsl, rel = g.to_global(q[0], q[1], q[2])
        rpy = frames.euler_ned(q[3:7])
        vn, ve, vd = v[1], v[0], -v[2]
        volts = float(st.battery_v) if st.battery_v > 0 else 16.8
        return {"ms": int(t * 1000), "lat": int(round(lat * 1e7)), "lon": int(round(lon * 1e7)),
                "amsl_mm": int(round(amsl * 1000)), "rel_mm": int(round(rel * 1000)),
                "vn_cm": int(vn * 100), "ve_cm": int(ve * 100), "vd_cm": int(vd * 100),
                "hdg_cdeg": int(math.degrees(rpy[2]) % 360 * 100),
                "ned": g.world_to_ned(q[0], q[1], q[2]), "vned": (vn, ve, vd), "rpy": rpy,
                "rates": (v[3], -v[4], -v[5]), "mv": int(volts * 1000),
                "ca": int(st.power / volts * 100), "pct": int(round(100 * st.battery_remaining)),
                "landed": self.landed_state(), "gs_cm": int(math.hypot(vn, ve) * 100),
                "cog_cdeg": int(math.degrees(math.atan2(ve, vn)) % 360 * 100),
                "home": self._home_int,
                "mission_seq": self.mi, "mission_n": len(self.link.mission)}

    # -- the simulation's step -------------------------------------------------------------
    def decide(self, t: float, drone) -> None:
        self.t_last = t
        if self._w0 is None:
            self._w0 = time.monotonic() - t / self.speed
        now = self._pace(t)
        self.n_steps += 1
        if self.stages.grounded:
            self._preflight(t)
            now = time.monotonic()
        self.wall = self._w0 + t / self.speed
        if now >= self.deadline:
            self.run.event(t, "app_timeout")
            self.run.stop("app_timeout")
            return
        if now >= self._next_poll:
            self._next_poll = now + 0.25
            self._check_app(t)
        pend = self._pending
        while pend and pend[0][0] <= self.wall:  # the rest arrived after this step
            self.handle(t, pend.popleft()[1])
        self._modes(t, self.wall)
        if self.in_air:
            self._geofence(t)
        if self.mission_active:
            self.mission_step(t)
        if t >= self._next_tel:
            self._telemetry(t, t)
        link = self.link
        if link.pending and now - link.queued_at >= SLEEP_MIN_S:   # not sleeping: behind
            link.flush()

    def _pace(self, t: float) -> float:
        """Wait until step ``t`` is to be computed on the paced clock; return the wall
        time (time.monotonic()). What the app sees is on time: a step that sends
        telemetry is computed at its paced wall time, and a message acts at the first
        step whose paced wall time follows its arrival, computed then (its COMMAND_ACK
        goes out then). The steps in between, which the app cannot see, are computed
        late, in one burst when the next of those comes: the thread sleeps until the
        next telemetry, a message's arrival or the deadline (at 1x 10 wake-ups a second,
        the telemetry's rate, instead of one per 40 ms step; the app's exit is checked
        at those, every 0.25 to 0.5 s). Never more than ``SLEEP_MIN_S`` early; falling
        behind is measured as ``lag``."""
        inbox, pend, w0, spd = self.link.inbox, self._pending, self._w0, self.speed
        assert w0 is not None
        wk = w0 + t / spd
        nt = self._next_tel
        if nt <= t:
            w_tel = wk
        elif math.isinf(nt):
            w_tel = math.inf
        else:                   # the first step at or after the telemetry (t >= nt there)
            k = math.ceil((nt - t) / PERIOD_S - 1e-6)
            if round(t + k * PERIOD_S, 9) < nt:       # 1.4 < 1.4000000000000001: one more
                k += 1
            w_tel = w0 + (t + k * PERIOD_S) / spd
        while True:
            while not inbox.empty():
                pend.append(inbox.get())
            now = time.monotonic()
            until = max(wk, min(w_tel, pend[0][0] if pend else math.inf,
                                self._next_poll + 0.25, self.deadline))
            ahead = until - now
            if ahead <= SLEEP_MIN_S:            # fewer, longer sleeps: each is a wake-up
                if ahead < 0.0:
                    self.lag_max = max(self.lag_max, -ahead)
                    self.lag_sum -= ahead
                return now
            self.link.flush()                   # what this burst computed, in one datagram
            if pend:                            # a message acts at this step: on time
                time.sleep(ahead)
                continue
            try:
                pend.append(inbox.get(timeout=ahead))
            except queue.Empty:
                pass

    def _telemetry(self, clock: float, t: float) -> None:
        """Queue the messages due at ``clock`` (s; each stream on its own grid of 1/rate
        s, so a 10 Hz stream sends 10 a second, not one per 3 steps of 40 ms), stamped
        with the simulated time ``t``."""
        due = [n for n, at in self._due.items() if clock >= at]
        if due:
            snap = self.snapshot(t)
            for n in due:
                r = self.rates[n]
                nxt = self._due[n] + 1.0 / r if r > 0 else math.inf
                self._due[n] = nxt if nxt > clock else clock + 1.0 / r    # fell behind: resync
            self.link.queue_telemetry(due, snap)
        self._next_tel = min(self._due.values())

    def _preflight(self, t: float) -> None:
        """On the pad before the take-off the simulated clock stands still (lockstep with
        the app): commands are answered and telemetry sent on the wall clock until one of
        them ends the pre-flight (take-off, mission, offboard), the app exits or the
        deadline passes. So the flight does not depend on how long the app took to
        start, connect and arm (the same KPIs at every speed)."""
        inbox, w0 = self.link.inbox, time.monotonic()
        self._due = dict.fromkeys(self._due, 0.0)
        self._next_tel = 0.0
        while self.stages.grounded:
            now = time.monotonic()
            if now >= self.deadline or self._app_gone:
                return
            if now >= self._next_poll:
                self._next_poll = now + 0.25
                self._check_app(t)
            if now - w0 >= self._next_tel:      # the stream rates, on the wall clock
                self._telemetry(now - w0, t)
                self.link.flush()
            if self._pending:
                self.wall = now
                self.handle(t, self._pending.popleft()[1])
                continue
            wait = min(self._next_tel - (now - w0), self._next_poll - now, self.deadline - now)
            try:
                _, msg = inbox.get(timeout=max(0.0, wait))
            except queue.Empty:
                continue
            self.wall = time.monotonic()        # the clock of the offboard setpoints' age
            self.handle(t, msg)
        self._w0 = time.monotonic() - t / self.speed     # paced again from here
        self._due = dict.fromkeys(self._due, t)
        self._next_tel = t

    def _modes(self, t: float, now: float) -> None:
        """What the stages did on their own: climb done, landed, returning."""
        stage = self.st.stage
        if stage == PILOT and self.mode == "TAKEOFF" and not self.mission_active:
            self.mode = "HOLD"
            self.hold(t)
        elif stage == RETURN:
            self.mode = "RTL"
        elif stage == LAND and self.mode not in ("LAND", "RTL"):
            self.mode = "LAND"
        if self.mode == "OFFBOARD" and (self.setpoint is None
                                        or now - self.setpoint[3] > OFFBOARD_LOSS_S):
            self.run.event(t, "app_offboard_lost", after_s=OFFBOARD_LOSS_S)
            self.mode = "HOLD"
            self.hold(t)

    def _check_app(self, t: float) -> None:
        p = self.proc
        if p is None or self._app_gone or p.poll() is None:
            return
        self._app_gone = True
        self.run.event(t, "app_exited", exit_code=p.returncode)
        if not self.in_air:
            self.run.stop("app_exited")
        elif self.st.stage in (PILOT, TAKEOFF):    # link lost in the air: PX4's RTL failsafe
            self.mode = "RTL"
            self.stages.go_home(t)

    def finish(self, t: float) -> None:
        super().finish(t)
        self.armed = False
        if self.mode not in ("READY",):
            self.mode = "LAND" if self.mode in ("LAND", "RTL") else self.mode
        self.link.flush()
        self.link.snap = self.snapshot(t)
        self.link.sim_running = False
        self.link.wake()

    # -- flying ----------------------------------------------------------------------------
    def fly(self, t: float, pilot) -> None:
        """Fly ``pilot`` from now (also during the take-off climb, as PX4 allows)."""
        self.stages.replace_pilot(t, pilot)

    def hold(self, t: float) -> None:
        q = self.st.qc
        self.sp_pilot = None
        sp = Setpoint(q[2], self.cruise, pos=(q[0], q[1], q[2]), yaw=self._yaw())
        self.fly(t, sp)

    def _yaw(self) -> float:
        return yaw_of(self.st.qc[3:7])

    def goto(self, t: float, pos, yaw: float | None, speed: float | None = None) -> int:
        """Fly to ``pos`` (world) and hold there, heading ``yaw`` (None: keep it)."""
        try:
            self._in_reach(pos)
        except ConfigError as exc:
            self.run.event(t, "app_refused", reason=str(exc))
            return M.MAV_RESULT_DENIED
        if self.outside_fence(t, pos):      # acknowledged; the drone stays where it is
            return M.MAV_RESULT_ACCEPTED
        sp = Setpoint(pos[2], speed or self.cruise, pos=tuple(pos),
                      yaw=self._yaw() if yaw is None else yaw)
        self.fly(t, sp)
        return M.MAV_RESULT_ACCEPTED

    def _in_reach(self, pos) -> None:
        far = max(abs(pos[0] - self.st.home[0]), abs(pos[1] - self.st.home[1]))
        if far > limits.MAX_EXTENT_M or pos[2] - self.st.home[2] < 0.5:
            raise ConfigError(f"app: position {tuple(round(c, 1) for c in pos)} is out of "
                              f"reach (within {limits.MAX_EXTENT_M:g} m of home, at least "
                              f"0.5 m above it)")

    # -- the link's callbacks (its thread) --------------------------------------------------
    def mission_uploaded(self) -> None:
        self._reset_asked = True

    def refused_item(self, seq: int, name: str, why: str) -> None:
        self.unsupported += 1
        self.run.event(self.t_last, "app_mission_refused", seq=int(seq), item=name, reason=why)

    def not_emulated(self, kind: str, what: str, reason: str | None = None) -> None:
        """The app sent ``kind``, an input PX4 flies and this front-end does not (named
        once per kind; the link's thread)."""
        self.unsupported += 1
        self.run.event(self.t_last, "app_not_emulated", message=kind,
                       reason=reason or f"{what} are not flown")

    def off_flight(self, msg) -> None:
        """A command while no flight is being simulated (after it ended)."""
        kind = msg.get_type()
        if not kind.startswith("COMMAND"):
            return
        c = msg.command
        if c in self.requests:
            self.link.ack(c, self.request(msg))
            return
        disarm = c == M.MAV_CMD_COMPONENT_ARM_DISARM and msg.param1 < 0.5
        res = M.MAV_RESULT_ACCEPTED if disarm else M.MAV_RESULT_DENIED
        self.count(c, res)
        self.link.ack(c, res)
