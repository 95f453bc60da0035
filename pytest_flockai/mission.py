"""Mission: one drone, one pilot, a world and tasks, flown on one simulated clock.

The loop runs at the control rate; MuJoCo advances ``physics_hz / control_hz``
substeps per tick in one C call. Each control tick: read the state, advance the
wind, apply body drag through the air-relative velocity, get the setpoint from
the stage (take-off, pilot, return, landing), run the cascaded controller, feed
the energy meter, classify the flight phase, record telemetry at its own rate,
step the physics, check for crashes and divergence. No pandas, dicts or
numpy allocation per tick; the DataFrame is built once at the end.
"""

from __future__ import annotations

import math
import time as _time
from numbers import Real

import mujoco
import numpy as np
import pandas as pd

from . import _check
from .airframe.drone import Drone, G
from .airframe.model import build_spec
from .control.controller import CascadedController
from .control.estimator import NavEstimator
from .control.pilots import Pilot
from .control.trajectory import Leg, Path
from .energy.components import Usage
from .energy.model import Meter
from .errors import ConfigError, SimulationError
from .result import FlightResult
from .probes.hub import ProbeHub, RunView, resolve_probes
from .probes.telemetry import TelemetryRecorder
from .recording import publish
from .world.wind import Wind

UNTIL = ("landed", "battery_depleted", "battery_reserve")
_NAV_SENSORS = {"gps", "imu", "compass", "barometer", "rangefinder", "battery"}
OS_MEMORY_MB = 250.0     # estimate: Raspberry Pi OS Lite + flight software resident set
PHASES = ("takeoff", "hover", "move", "accelerating", "landing", "landed")
_TAKEOFF, _HOVER, _MOVE, _ACCEL, _LANDING, _LANDED = range(6)
# mission stages (what the drone is commanded to do)
_S_TAKEOFF, _S_PILOT, _S_RETURN, _S_LAND, _S_DONE = range(5)
STAGES = ("takeoff", "pilot", "return", "landing", "done")

HOVER_SPEED = 0.5        # m/s: below this an airborne drone is hovering
ACCEL_THRESHOLD = 0.5    # m/s^2: above this it is accelerating
CRASH_SPEED = 2.0        # m/s: touching anything faster than this is a crash
CLOCK_EPS = 1e-6         # s: tolerance of the sub-clocks against the summed physics time
SEEDS = {"wind": 0, "sensors": 1, "tasks": 2, "link": 3, "world": 4, "probes": 5}


def to_body(q, x, y, z):
    """A world-frame vector in the body frame of the attitude quaternion q[3:7] (R^T v)."""
    qw, qx, qy, qz = q[3], q[4], q[5], q[6]
    xx, yy, zz = qx * qx, qy * qy, qz * qz
    xy, xz, yz = qx * qy, qx * qz, qy * qz
    wx, wy, wz = qw * qx, qw * qy, qw * qz
    return ((1 - 2 * (yy + zz)) * x + 2 * (xy + wz) * y + 2 * (xz - wy) * z,
            2 * (xy - wz) * x + (1 - 2 * (xx + zz)) * y + 2 * (yz + wx) * z,
            2 * (xz + wy) * x + 2 * (yz - wx) * y + (1 - 2 * (xx + yy)) * z)


def seed_sequence(seed: int, component: str) -> np.random.SeedSequence:
    """The SeedSequence of one component of a mission (fixed spawn keys)."""
    return np.random.SeedSequence(seed, spawn_key=(SEEDS[component],))


class Mission:
    """A flight to simulate: ``Mission(drone, pilot, ...).run() -> FlightResult``.

    until: "landed" (fly the plan, return home, land), "battery_depleted" (fly
    until the battery is empty), "battery_reserve" (return home and land when the
    battery falls to its reserve), or a number of simulated seconds.
    """

    def __init__(self, drone: Drone, pilot: Pilot, world=None, tasks=(), probes=None, wind=None,
                 seed: int = 0, until="landed", *, return_home: bool = True,
                 max_time_s: float = 4 * 3600.0, telemetry_hz: float = 10.0,
                 energy_hz: float = 20.0, sensors=(), fly_on: str = "truth",
                 dataset_dir=None, dataset_period_s: float = 1.0,
                 climb_speed: float = 2.0, descent_speed: float = 1.0, name: str | None = None):
        if not isinstance(drone, Drone):
            raise ConfigError(f"Mission: drone = {drone!r} is not a Drone; use fa.drone(name)")
        if not isinstance(pilot, Pilot):
            raise ConfigError(f"Mission: pilot = {pilot!r} is not a Pilot (fa.pilots.Hover, "
                              f"Waypoints, ZigZag, Orbit or a Pilot subclass)")
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise ConfigError(f"Mission: seed = {seed!r} is not allowed; expected an integer >= 0")
        if isinstance(until, str):
            _check.choice("until", until, UNTIL, where="Mission")
        elif isinstance(until, Real) and not isinstance(until, bool):
            until = _check.positive("until", until, where="Mission")
        else:
            raise ConfigError(f"Mission: until = {until!r} is not allowed; allowed: "
                              f"{', '.join(map(repr, UNTIL))} or a number of seconds > 0")
        self.drone = drone
        self.pilot = pilot
        self.world = world
        self.tasks = _check_tasks(tasks, drone, sensors)
        self.probes = resolve_probes(probes)
        self.subscribers: list = []
        self.wind = Wind.coerce(wind)
        self.seed = int(seed)
        self.until = until
        self.return_home = bool(return_home)
        self.max_time_s = _check.positive("max_time_s", max_time_s, where="Mission")
        self.telemetry_hz = _check.positive("telemetry_hz", telemetry_hz, where="Mission")
        self.energy_hz = _check.positive("energy_hz", energy_hz, where="Mission")
        self.climb_speed = _check.positive("climb_speed", climb_speed, where="Mission")
        self.descent_speed = _check.positive("descent_speed", descent_speed, where="Mission")
        self.name = name
        self.sensors = list(sensors or ())
        from .sensors import Sensor
        for i, sn in enumerate(self.sensors):
            if not isinstance(sn, Sensor):
                raise ConfigError(f"Mission: sensors[{i}] = {sn!r} is not a Sensor")
        self.fly_on = _check.choice("fly_on", fly_on, ("truth", "estimate"), where="Mission")
        self.dataset_dir = dataset_dir
        self.dataset_period_s = _check.positive("dataset_period_s", dataset_period_s, where="Mission")
        if dataset_dir is not None and drone.camera is None:
            raise ConfigError(f"Mission: dataset_dir = {str(dataset_dir)!r} needs a camera, and "
                              f"{drone.name} has no [camera] section")

    def subscribe(self, target) -> "Mission":
        """Receive probe samples live: ``target`` is a callable ``fn(sample)`` or a
        ``queue.Queue``; each sample is ``{"t": s, "probe": name, "values": {...}}``."""
        if not (callable(target) or hasattr(target, "put_nowait")):
            raise ConfigError(f"Mission.subscribe: {target!r} is neither callable nor a queue")
        self.subscribers.append(target)
        return self

    def scenario(self) -> dict:
        return {
            "name": self.name, "drone": self.drone.to_dict(), "pilot": self.pilot.to_dict(),
            "world": self.world.to_dict() if self.world is not None else {"name": "empty"},
            "wind": self.wind.to_dict() if self.wind is not None else None,
            "seed": self.seed, "until": self.until, "return_home": self.return_home,
            "tasks": [getattr(t, "to_dict", lambda: repr(t))() for t in self.tasks],
            "probes": [p.to_dict() for p in self.probes],
            "sensors": [sn.name for sn in self.drone.extra_sensors + self.sensors],
            "fly_on": self.fly_on,
        }

    def __repr__(self):
        return f"Mission({self.drone.name!r}, {self.pilot!r}, seed={self.seed}, until={self.until!r})"

    # ------------------------------------------------------------------
    def run(self) -> FlightResult:
        wall0 = _time.perf_counter()
        run = _Run(self)
        try:
            run.loop()
        except SimulationError as exc:
            exc.result = run.result(_time.perf_counter() - wall0, end_reason="diverged")
            publish(exc.result, self)
            raise
        result = run.result(_time.perf_counter() - wall0)
        publish(result, self)
        return result


def _check_tasks(tasks, drone, sensors):
    from .ml import Task
    from .probes.builtin import BUILTIN
    tasks = tuple(tasks or ())
    names = set()
    reserved = {cls.name for cls in BUILTIN}
    extra = {sn.name for sn in list(drone.extra_sensors) + list(sensors or ())}
    for i, tk in enumerate(tasks):
        if not isinstance(tk, Task):
            raise ConfigError(f"Mission: tasks[{i}] = {tk!r} is not a Task; use "
                              f"fa.Task(model, sensor='camera', period_s=5.0, ...)")
        if tk.name in names:
            raise ConfigError(f"Mission: two tasks are named {tk.name!r}; give them name=... "
                              f"(task names prefix their KPIs)")
        if tk.name in reserved:
            raise ConfigError(f"Mission: task name {tk.name!r} clashes with a built-in probe; "
                              f"give the task another name=")
        names.add(tk.name)
        if tk.sensor == "camera":
            if drone.camera is None and "camera" not in extra:
                raise ConfigError(f"task {tk.name!r} reads sensor 'camera', but {drone.name} has no "
                                  f"[camera] section; add one to the blueprint or add a camera "
                                  f"sensor (drone.add_sensor(fa.sensors.ReplayCamera(...)))")
        elif tk.sensor not in extra and tk.sensor not in _NAV_SENSORS:
            raise ConfigError(f"task {tk.name!r} reads sensor {tk.sensor!r}, which is not on "
                              f"{drone.name}; add it with drone.add_sensor(...) or "
                              f"Mission(sensors=[...]); built in: camera, "
                              f"{', '.join(sorted(_NAV_SENSORS))}")
    onboard = {tk.device.name for tk in tasks if tk.execution == "onboard"}
    if len(onboard) > 1:
        raise ConfigError(f"Mission: on-board tasks name different computers ({', '.join(sorted(onboard))}); "
                          f"a drone has one on-board computer: give them the same device")
    return tasks


class _Run:
    """State of one flight. Split from Mission so a Mission can be flown again."""

    def __init__(self, mission: Mission):
        self.mission = m = mission
        drone = m.drone
        drone.check()
        sim = drone.sim
        if sim.physics_hz < sim.control_hz:
            raise ConfigError(f"{drone.name} [sim]: physics_hz = {sim.physics_hz:g} must be >= "
                              f"control_hz = {sim.control_hz:g}")
        self.substeps = max(1, int(round(sim.physics_hz / sim.control_hz)))
        physics_dt = 1.0 / sim.physics_hz
        self.ctrl_dt = physics_dt * self.substeps
        self.suite = self._sensor_suite(m, drone)
        spec = build_spec(drone, m.world, physics_dt=physics_dt)
        self.suite.add_to_spec(spec, "drone")
        self.model = spec.compile()
        self.data = mujoco.MjData(self.model)
        mujoco.mj_forward(self.model, self.data)
        self.battery_remaining = 1.0
        if "battery" in self.suite and getattr(self.suite["battery"], "source", None) is None:
            self.suite["battery"].source = lambda: self.battery_remaining
        self.suite.bind(self.model, self.data, seed_sequence(m.seed, "sensors"), world=m.world)
        self.estimator = NavEstimator() if m.fly_on == "estimate" else None
        self.controller = CascadedController(drone, self.ctrl_dt)
        self.meter = Meter(self._energy_model(drone), drone)
        # ML tasks: one runner each, seeded per task from the mission seed
        self.runners = []
        children = seed_sequence(m.seed, "tasks").spawn(len(m.tasks)) if m.tasks else []
        from .ml.task import DeviceClock
        onboard_clock = DeviceClock()          # one on-board computer, shared by its tasks
        for tk, child in zip(m.tasks, children):
            r = tk.runner()
            r.bind(np.random.default_rng(child), t0=0.0, device_clock=onboard_clock)
            self.runners.append(r)
        self.recorder = _DatasetRecorder(m.dataset_period_s) if m.dataset_dir is not None else None
        self.cpu_time_s = 0.0
        self.in_view: list = []          # (t, people in view) at every rendered frame
        self.capture_pos: dict = {}      # t -> drone (x, y, z) at captures
        dev = self._onboard_device(m, drone)
        mem = OS_MEMORY_MB + sum(4e-6 * float(getattr(tk.model, "params", 0) or 0) for tk in m.tasks
                                 if tk.execution == "onboard")
        self.mem_utilization = min(1.0, mem / dev.memory_mb) if dev is not None else 0.0
        self.usage = Usage(drone.airframe.rotor_count)
        self.events: list[dict] = []
        self.view = RunView(mission, self.meter)
        from .probes.builtin import TaskProbe
        task_probes = [TaskProbe(tk.name) for tk in mission.tasks]
        self.hub = ProbeHub(list(mission.probes) + task_probes, mission.subscribers)
        self.hub.bind(self.view)
        self.phase_ticks = [0] * 6
        self.book_dt = self.ctrl_dt
        self.dist = self.vmax = self.track_max = 0.0
        self.bytes_out = self.bytes_in = self.pkts_out = self.pkts_in = 0
        self.end_reason = "running"
        self.crashed = False
        self.t_land = None

    # -- the loop --------------------------------------------------------
    def loop(self):
        ms, drone = self.mission, self.mission.drone
        model, d = self.model, self.data
        ctrl = self.controller
        meter, u = self.meter, self.usage
        n_rot = drone.airframe.rotor_count
        dt = self.ctrl_dt
        nsub = self.substeps
        until = ms.until
        t_end = float(until) if not isinstance(until, str) else ms.max_time_s
        t_end = min(t_end, ms.max_time_s)
        e_usable = drone.battery.energy_j
        reserve_e = drone.battery.reserve_fraction * e_usable
        use_reserve = until == "battery_reserve"
        # wind
        wind = ms.wind.sampler(np.random.default_rng(seed_sequence(ms.seed, "wind")), dt) \
            if ms.wind is not None else None
        w = (0.0, 0.0, 0.0)
        mwind = model.opt.wind
        if wind is not None:
            mwind[:] = ms.wind.mean
        qpos, qvel, act, dctrl = d.qpos, d.qvel, d.act, d.ctrl
        # accel limit of trajectories: a quarter of the thrust margin, at most 2.5 m/s^2,
        # and no more than the velocity loop can follow (1.5 x its bandwidth, in m/s^2 per m/s)
        accel = min(2.5, 0.25 * (drone.thrust_to_weight - 1.0) * G, 1.5 * ctrl.k_vel)
        self.traj_accel = accel
        pilot = ms.pilot
        ground_z = float(qpos[2])
        self.home = home = (0.0, 0.0, ground_z)
        alt = float(pilot.altitude)
        stage = _S_TAKEOFF
        path = Path([Leg(home, (0.0, 0.0, alt), ms.climb_speed, accel)])
        t_stage = 0.0
        sp = [0.0, 0.0, ground_z, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
        # radio heartbeats (health checks) to the ground station
        radio = drone.radio
        hb_period = radio.heartbeat_period_s
        hb_bytes = int(radio.heartbeat_bytes)
        next_hb = 0.0
        # phase bookkeeping (whole ticks, so times add up exactly)
        phase_ticks = self.phase_ticks
        last_phase = -1
        phase = _TAKEOFF
        self._event(0.0, "stage", stage="takeoff")
        dist = 0.0
        vmax = 0.0
        track_max = 0.0
        pvx = pvy = pvz = 0.0
        acc_f = 0.0
        # bookkeeping (phases, distance, tracking error) at 50 Hz, or every tick if slower
        book_dt = self.book_dt = max(dt, 0.02 // dt * dt)
        hub = self.hub
        suite, navest = self.suite, self.estimator
        consumers = list(self.runners) + ([self.recorder] if self.recorder is not None else [])
        task_next = min((c.next_frame_t for c in consumers), default=math.inf)
        next_book = 0.0
        t_book = 0.0
        a_filt = math.exp(-book_dt / 0.2)  # 0.2 s smoothing of |dv/dt|
        # telemetry
        rec_dt = 1.0 / ms.telemetry_hz
        next_rec = 0.0
        est = (float(until) if not isinstance(until, str) else 1800.0)
        self.rec = TelemetryRecorder(int(min(est, ms.max_time_s) * ms.telemetry_hz) + 16, n_rot,
                                     meter, d, self.suite, self.estimator)
        record = self.rec.record
        energy_j = 0.0
        e_period = 1.0 / ms.energy_hz
        next_e = e_period        # the first interval (0, e_period] is charged at its end
        t_e = 0.0
        power = 0.0
        tx_b = tx_p = rx_b = rx_p = 0
        airborne = True
        t = 0.0
        self.t_land = None
        step = mujoco.mj_step
        sqrt = math.sqrt
        cupdate, pupdate, mstep = ctrl.update, pilot.update, meter.step
        rot_idx = range(n_rot)
        while True:
            t = d.time
            q = qpos.tolist()
            v = qvel.tolist()
            z, vx, vy, vz = q[2], v[0], v[1], v[2]
            if not (z == z and abs(z) < 1e5 and vx == vx):
                raise SimulationError(
                    f"simulation diverged at t = {t:.3f} s (position or velocity not finite: "
                    f"z = {z!r}, vx = {vx!r}); check the blueprint's inertia and rotor "
                    f"coefficients or lower the physics timestep")
            # -- sensors (only those something reads) and the estimate ----------
            if t >= suite.next_due:
                suite.step(t, d)
            # ML tasks and the dataset recorder take frames when due, while the
            # drone surveys (pilot and return stages; not on the ground)
            if t >= task_next - CLOCK_EPS and (stage == _S_PILOT or stage == _S_RETURN):
                task_next = self._feed(t, q, consumers)
            # the pilot and controller fly on qc/vc (estimates or truth); everything
            # measured (phases, distance, tracking, telemetry) uses the true state
            if navest is not None:
                qc, vc = navest.update(t, q, v, suite)
            else:
                qc, vc = q, v
            # -- setpoint by stage --------------------------------------
            if stage == _S_PILOT:
                if pupdate(t, (qc[0], qc[1], qc[2], vc[0], vc[1], vc[2]), sp):
                    stage, path, t_stage = self._after_pilot(t, q, sp)
            elif stage != _S_DONE:
                if path.fill(t - t_stage, sp):
                    if stage == _S_TAKEOFF:
                        stage = _S_PILOT
                        pilot.start(t, (qc[0], qc[1], qc[2]), accel)
                        self._event(t, "stage", stage="pilot")
                        pilot.update(t, (qc[0], qc[1], qc[2], vc[0], vc[1], vc[2]), sp)
                    elif stage == _S_RETURN:
                        stage, t_stage = _S_LAND, t
                        path = Path([Leg((sp[0], sp[1], sp[2]), (sp[0], sp[1], ground_z - 0.5),
                                         ms.descent_speed, accel)])
                        self._event(t, "stage", stage="landing")
            if stage == _S_LAND and d.ncon > 0 and abs(vz) < 0.3:
                stage = _S_DONE
                self.t_land = t
                self._event(t, "stage", stage="landed")
            # -- control ---------------------------------------------------
            if stage == _S_DONE:
                dctrl[:] = 0.0
                airborne = False
            else:
                f = cupdate(qc, vc, sp)
                if f[0] != f[0]:
                    raise SimulationError(
                        f"the controller produced NaN rotor thrust at t = {t:.3f} s (stage "
                        f"{STAGES[stage]}, setpoint {[round(x, 3) for x in sp]}); a pilot or "
                        f"estimate gave a non-finite value")
                for i in rot_idx:
                    dctrl[i] = f[i]
            # -- air: MuJoCo applies body drag against opt.wind every substep ----
            if wind is not None:
                w = wind.step()
                mwind[0], mwind[1], mwind[2] = w
            # -- radio and energy (energy on its own clock; usage accumulates) --
            if t >= next_hb - CLOCK_EPS:
                next_hb += hb_period
                tx_b += hb_bytes
                tx_p += 1
                rx_b += 64
                rx_p += 1
            if t >= next_e - CLOCK_EPS:
                # usage of the interval (t_e, t]: bytes and busy time accumulated,
                # rotor thrust and airspeed sampled now
                edt = t - t_e
                u.dt = edt
                u.t = t
                u.airborne = airborne
                u.thrust = act.tolist()
                u.v_rel_body = to_body(q, vx - w[0], vy - w[1], vz - w[2])
                if self.runners:
                    busy, tb, tp, rb, rp = self._task_usage(t)
                    tx_b += tb
                    tx_p += tp
                    rx_b += rb
                    rx_p += rp
                    u.soc_busy = min(1.0, busy / edt) if edt > 0 else 0.0
                u.tx_bytes, u.tx_packets, u.rx_bytes, u.rx_packets = tx_b, tx_p, rx_b, rx_p
                self.bytes_out += tx_b
                self.bytes_in += rx_b
                self.pkts_out += tx_p
                self.pkts_in += rx_p
                tx_b = tx_p = rx_b = rx_p = 0
                power = mstep(u)
                energy_j += power * edt
                self.battery_remaining = max(0.0, 1.0 - energy_j / e_usable)
                t_e = t
                next_e += e_period
            # -- phases and flight KPIs, on the bookkeeping clock -----------------
            speed = sqrt(vx * vx + vy * vy + vz * vz)
            if t >= next_book - CLOCK_EPS:
                bdt = t - t_book
                t_book = t
                next_book += book_dt
                if airborne:
                    if bdt > 0.0:
                        dv = sqrt((vx - pvx) ** 2 + (vy - pvy) ** 2 + (vz - pvz) ** 2) / bdt
                        acc_f = a_filt * acc_f + (1.0 - a_filt) * dv
                    if stage == _S_TAKEOFF:
                        phase = _TAKEOFF
                    elif stage == _S_LAND:
                        phase = _LANDING
                    elif speed < HOVER_SPEED:
                        phase = _HOVER
                    elif acc_f > ACCEL_THRESHOLD:
                        phase = _ACCEL
                    else:
                        phase = _MOVE
                    phase_ticks[phase] += 1
                    if phase != last_phase:
                        self._event(t, "phase", phase=PHASES[phase])
                        last_phase = phase
                    dist += speed * book_dt
                    if speed > vmax:
                        vmax = speed
                    if stage == _S_PILOT:
                        ex, ey, ez = q[0] - sp[0], q[1] - sp[1], z - sp[2]
                        e = sqrt(ex * ex + ey * ey + ez * ez)
                        if e > track_max:
                            track_max = e
                else:
                    phase = _LANDED
                    if last_phase != _LANDED:
                        self._event(t, "phase", phase="landed")
                        last_phase = _LANDED
                pvx, pvy, pvz = vx, vy, vz
            # -- probes, each on its own period ----------------------------------
            if t >= hub.next_due - CLOCK_EPS:
                self.dist, self.vmax, self.track_max = dist, vmax, track_max
                self._sync_view(t, q, v, stage)
                hub.sample(t, self.view)
            # -- telemetry ------------------------------------------------
            if t >= next_rec - CLOCK_EPS:
                next_rec += rec_dt
                record(t, q, v, sp, w, phase, stage, power, energy_j, e_usable)
            # -- end conditions -------------------------------------------
            if stage == _S_DONE:
                self.end_reason = "landed"
                break
            if energy_j >= e_usable:
                self.end_reason = "battery_depleted"
                self._event(t, "battery_depleted")
                break
            if use_reserve and stage == _S_PILOT and e_usable - energy_j <= reserve_e:
                self._event(t, "battery_reserve", remaining=(e_usable - energy_j) / e_usable)
                stage, path, t_stage = self._after_pilot(t, q, sp, force_home=True)
            if t + 0.5 * dt >= t_end:
                self.end_reason = "time" if not isinstance(until, str) else "time_cap"
                break
            # -- physics --------------------------------------------------
            step(model, d, nsub)
            if d.ncon > 0 and stage != _S_DONE:
                if self._impact(d, stage, speed, q):
                    self.crashed = True
                    self.end_reason = "crashed"
                    self._event(d.time, "crash", speed=speed)
                    break
            if d.time < t:
                raise SimulationError(
                    f"MuJoCo reset the simulation at t = {t:.3f} s (unstable physics: "
                    f"{_warnings(d)}); check the blueprint or lower the physics timestep")
        t = d.time
        if self.runners:
            busy, tb, tp, rb, rp = self._task_usage(t)
            tx_b, tx_p, rx_b, rx_p = tx_b + tb, tx_p + tp, rx_b + rb, rx_p + rp
            u.soc_busy = min(1.0, busy / (t - t_e)) if t > t_e else 0.0
        if t > t_e:   # charge the last partial energy interval
            u.dt, u.t, u.airborne = t - t_e, t, airborne
            u.thrust = act.tolist()
            u.tx_bytes, u.tx_packets, u.rx_bytes, u.rx_packets = tx_b, tx_p, rx_b, rx_p
            self.bytes_out += tx_b
            self.bytes_in += rx_b
            self.pkts_out += tx_p
            self.pkts_in += rx_p
            energy_j += meter.step(u) * (t - t_e)
        self.t_final = t
        self.dist, self.vmax, self.track_max = dist, vmax, track_max
        q = qpos.tolist()
        record(t, q, qvel.tolist(), sp, w, _LANDED if not airborne else phase, stage,
                     meter.last_power, energy_j, e_usable)

    @staticmethod
    def _sensor_suite(m, drone):
        """The sensors read in this flight: the ones added to the drone or the
        mission, GPS and barometer when flying on estimates, and the blueprint's
        camera (rendered only when something asks for a frame). The blueprint's
        other sensors draw power through the energy model but are not read."""
        from .sensors import GPS, Barometer, Camera, SensorSuite
        chosen = list(drone.extra_sensors) + list(m.sensors)
        names = {sn.name for sn in chosen}
        from .sensors import IMU, BatterySensor, Compass, Rangefinder
        nav = {"gps": GPS, "barometer": Barometer, "imu": IMU, "compass": Compass,
               "rangefinder": Rangefinder, "battery": BatterySensor}
        wanted = [tk.sensor for tk in m.tasks if tk.sensor in nav]
        if m.fly_on == "estimate":
            wanted += ["gps", "barometer"]
        for name in wanted:
            if name not in names:
                chosen.append(nav[name]())
                names.add(name)
        if drone.camera is not None and "camera" not in names and (
                "camera" in drone.sensors or m.dataset_dir is not None
                or any(tk.sensor == "camera" for tk in m.tasks)):
            chosen.append(Camera.from_blueprint(drone))
        return SensorSuite(chosen)

    def _feed(self, t, q, consumers):
        """Give a frame (rendered once per tick) or sensor value to every due consumer."""
        cache = {}
        pos = (q[0], q[1], q[2])
        for c in consumers:
            if not c.due(t):
                continue
            name = getattr(c, "sensor", None) or c.task.sensor
            if name not in cache:
                if name not in self.suite:
                    cache[name] = (None, None)
                else:
                    value = self.suite.read(name, t, self.data)
                    truth = getattr(self.suite[name], "last_truth", None)
                    if truth is not None:
                        self.in_view.append((t, truth.count))
                    cache[name] = (value, truth)
                self.capture_pos[round(t, 6)] = pos
            value, truth = cache[name]
            c.on_frame(t, value, truth if not hasattr(truth, "count") else truth.count, pos) \
                if not isinstance(c, _DatasetRecorder) else c.on_frame(t, value, truth, pos)
        return min((c.next_frame_t for c in consumers), default=math.inf)

    def _task_usage(self, t):
        busy = 0.0
        tb = tp = rb = rp = 0
        for r in self.runners:
            r.advance(t)
            b, a1, a2, a3, a4 = r.take_usage()
            busy += b
            tb += a1
            tp += a2
            rb += a3
            rp += a4
        self.cpu_time_s += busy
        return busy, tb, tp, rb, rp

    def _task_kpis(self):
        """Combined KPIs over all tasks and each task's own."""
        by = {r.task.name: r.kpis() for r in self.runners}
        if len(self.runners) == 1:
            return next(iter(by.values())), by
        from .ml.metrics import percentile
        lat = [e.latency_s for r in self.runners for e in r.events if e.ok]
        comb = {"inference_count": float(len(lat)),
                "inference_latency_p50_s": percentile(lat, 50),
                "inference_latency_p95_s": percentile(lat, 95),
                "inference_latency_max_s": max(lat) if lat else math.nan,
                "frames_dropped": sum(k["frames_dropped"] for k in by.values()),
                "inference_failures": sum(k["inference_failures"] for k in by.values())}
        return comb, by

    @staticmethod
    def _onboard_device(m, drone):
        """The on-board computer: the on-board tasks' device, else the blueprint's."""
        from .compute import device
        for tk in m.tasks:
            if tk.execution == "onboard":
                return tk.device
        return device(drone.device) if drone.device != "none" else None

    def _energy_model(self, drone):
        """The drone's energy model for this flight: plus the power of sensors added
        to the drone or mission (in ``proc.sensors``), and with the on-board tasks'
        computer as ``proc.soc`` when it differs from the blueprint's."""
        from .energy import Constant, Group, SoC
        extra = [sn for sn in list(drone.extra_sensors) + list(self.mission.sensors)
                 if getattr(sn, "power_w", 0.0) > 0.0]
        dev = self._onboard_device(self.mission, drone)
        swap_soc = dev is not None and dev.name != drone.device
        if not extra and not swap_soc:
            return drone.energy
        model = drone.energy.copy()
        if swap_soc and "proc" in model:
            proc = model.component("proc")
            soc = SoC("soc", dev.idle_w, dev.active_w, f"on-board computer {dev.name}")
            if "soc" in proc:
                proc.replace("soc", soc)
            else:
                proc.add(soc)
        if not extra:
            return model
        proc = model.component("proc") if "proc" in model else None
        if proc is None:
            proc = Group("proc")
            model.add(proc)
        if "sensors" not in proc:
            proc.add(Group("sensors"))
        group = proc.component("sensors")
        for sn in extra:
            if sn.name not in group:
                group.add(Constant(sn.name, sn.power_w, f"{type(sn).__name__} sensor"))
        return model

    def _sync_view(self, t, q, v, stage):
        vw = self.view
        vw.t = t
        vw.position = (q[0], q[1], q[2])
        vw.velocity = (v[0], v[1], v[2])
        vw.stage = STAGES[stage]
        bd = self.book_dt
        vw.phase_time = [n * bd for n in self.phase_ticks]
        vw.distance_m, vw.max_speed_mps, vw.tracking_error_max_m = self.dist, self.vmax, self.track_max
        vw.crashed = self.crashed
        vw.bytes_in, vw.bytes_out = self.bytes_in, self.bytes_out
        vw.packets_in, vw.packets_out = self.pkts_in, self.pkts_out
        vw.cpu_time_s = self.cpu_time_s
        vw.mem_utilization = self.mem_utilization
        vw.sensors = self.suite.latest
        if self.runners:
            vw.task_kpis, vw.task_kpis_by_task = self._task_kpis()

    def _after_pilot(self, t, q, sp, force_home=False):
        ms = self.mission
        here = (sp[0], sp[1], sp[2])
        home_air = (self.home[0], self.home[1], sp[2])
        far = math.dist(here[:2], home_air[:2]) > 0.5
        if (ms.return_home or force_home) and far:
            self._event(t, "stage", stage="return")
            speed = getattr(ms.pilot, "speed", 5.0)
            return _S_RETURN, Path([Leg(here, home_air, speed, self.traj_accel)]), t
        self._event(t, "stage", stage="landing")
        return _S_LAND, Path([Leg(here, (here[0], here[1], self.home[2] - 0.5),
                                  ms.descent_speed, self.traj_accel)]), t

    def _impact(self, d, stage, speed, q):
        # flipped over, or touched anything faster than CRASH_SPEED
        R = d.xmat[1]
        if R[8] < 0.0:
            return True
        if stage == _S_TAKEOFF and q[2] < self.home[2] + 0.05:
            return False
        return speed > CRASH_SPEED

    def _event(self, t, kind, **info):
        self.events.append({"t": round(float(t), 6), "kind": kind, **info})

    # -- result --------------------------------------------------------------
    def result(self, wall, end_reason=None) -> FlightResult:
        if end_reason:
            self.end_reason = end_reason
        tel = self.rec.frame(PHASES, STAGES)
        kpis = self._kpis()
        frames = self.hub.frames()
        for name, df in frames.items():   # probe metrics into the telemetry, as of each row
            extra = [c for c in df.columns if c not in tel.columns]
            if extra and len(df) and len(tel):
                merged = pd.merge_asof(tel[[]].reset_index(), df[extra].reset_index(), on="t",
                                       direction="backward")
                for c in extra:
                    tel[c] = merged[c].to_numpy()
        scen = self.mission.scenario()
        scen["sim_time_s"] = float(getattr(self, "t_final", self.data.time))
        scen["physics_hz"] = self.mission.drone.sim.physics_hz
        scen["control_hz"] = 1.0 / self.ctrl_dt
        scen["controller_gains"] = self.controller.gains
        inf_events = []
        for r in self.runners:
            thr = r.task.crowd_threshold
            for e in r.events:
                d = e.to_dict()
                d["t"] = round(float(e.t_done if e.t_done is not None else e.t_capture), 6)
                pos = self.capture_pos.get(round(float(e.t_capture), 6))
                if pos is not None:
                    d["x"], d["y"], d["z"] = pos
                d["detected"] = bool(e.ok and e.count is not None and e.count >= thr)
                inf_events.append(d)
        events = sorted(self.events + self.hub.errors + inf_events, key=lambda e: e["t"])
        if self.in_view and len(tel):
            iv = pd.DataFrame(self.in_view, columns=["t", "people_in_view"]).drop_duplicates("t")
            merged = pd.merge_asof(tel[[]].reset_index(), iv, on="t", direction="nearest",
                                   tolerance=0.5 / self.mission.telemetry_hz)
            tel["people_in_view"] = merged["people_in_view"].to_numpy(dtype=float)
        if self.recorder is not None and self.recorder.records:
            from .sensors import export_dataset
            export_dataset(self.recorder.records, self.mission.dataset_dir)
        res = FlightResult(kpis, tel, events, scen, self.meter.breakdown(), self.end_reason, wall,
                           probe_samples=frames, probe_errors=list(self.hub.errors))
        w = self.mission.world
        res.people = np.asarray(w.people) if w is not None and hasattr(w, "people") else np.zeros((0, 3))
        return res

    def _kpis(self) -> dict:
        """Every KPI comes out of a probe: the final sample of each enabled probe."""
        d = self.data
        t = float(getattr(self, "t_final", d.time))
        self._sync_view(t, d.qpos.tolist(), d.qvel.tolist(), _S_DONE if self.t_land else _S_PILOT)
        self.hub.sample(t, self.view, force=True)
        return self.hub.kpis()


def _warnings(d) -> str:
    names = [w.name for w in mujoco.mjtWarning if w.name != "mjNWARNING"]
    hits = [n for n in names if d.warning[getattr(mujoco.mjtWarning, n)].number > 0]
    return ", ".join(hits) or "no MuJoCo warning recorded"


class _DatasetRecorder:
    """Takes camera frames and their truth every ``period_s`` for ``export_dataset``."""

    sensor = "camera"

    def __init__(self, period_s: float):
        self.period_s = period_s
        self.next_frame_t = 0.0
        self.records: list = []

    def due(self, t: float) -> bool:
        return t >= self.next_frame_t - CLOCK_EPS

    def on_frame(self, t, frame, truth, pos):
        if frame is not None:
            self.records.append((t, frame, truth))
        while self.next_frame_t <= t + CLOCK_EPS:
            self.next_frame_t += self.period_s
