"""Build a flight of 1..N drones from their plans: ONE MuJoCo model holding the
world and every drone, one MjData (one simulated clock), and per drone a
``Run``: its vehicle state, event log and clocked components, in the order the
loop steps them each tick (``steps.STEP_ORDER``).

A single Mission is a flight of one drone (named ``drone``, nothing prefixed:
its body is ``drone``, its rotors ``rotor0``...); the drones of a fleet are
prefixed with their names (``drone-2/rotor0``) and stand on their pads. A drone
alone in its model reads the MjData itself; a drone among others reads its
slice of it (``DroneData``: the same names, so every component runs unchanged).
"""

from __future__ import annotations

import copy

import numpy as np

from .._mujoco import mujoco
from ..airframe import model_cache
from ..airframe.mjspec import add_drone
from ..airframe.rotor_drag import RotorDrag
from ..clock import Clocked
from ..comm.traffic import Heartbeats, Traffic
from ..control.clocked import Control, Navigation
from ..control.estimator import NavEstimator
from ..control.stages import StageMachine, top_speed
from ..energy.integrator import EnergyIntegrator
from ..ml.scheduler import DatasetRecorder, TaskScheduler, memory_utilization
from ..probes.builtin import TaskProbe
from ..probes.hub import ProbeHub, RunView
from ..probes.telemetry import TelemetryRecorder, TelemetryStep
from ..sensors import GPS, IMU, Barometer, BatterySensor, Camera, Compass, Rangefinder, SensorSuite
from ..sensors.base import Sensing
from ..world.actors import ActorSet
from ..world.wind import WindStep
from . import parts, steps
from .book import FlightBook
from .ending import EndConditions, WallClockGuard
from .plan import FlightPlan, seed_sequence
from .probing import ProbeStep
from .state import EventLog, VehicleState

_NAV = {"gps": GPS, "barometer": Barometer, "imu": IMU, "compass": Compass,
        "rangefinder": Rangefinder, "battery": BatterySensor}
#: sensors that read the drone's own state only: they never look at a geom
BLIND = (IMU, GPS, Barometer, Compass, BatterySensor)


def sensor_suite(plan: FlightPlan, *, unread_camera: bool = True) -> SensorSuite:
    """The sensors read in this flight: the ones added to the drone or the
    mission, GPS and barometer when flying on estimates, and the blueprint's
    camera (rendered only when something asks for a frame). The blueprint's
    other sensors draw power through the energy model but are not read.
    ``unread_camera=False`` (a fleet's drones) leaves the camera out when no task
    reads it (it still draws power through the energy model)."""
    drone = plan.drone
    chosen = list(drone.extra_sensors) + list(plan.sensors)
    names = {sn.name for sn in chosen}
    wanted = [tk.sensor for tk in plan.tasks if tk.sensor in _NAV]
    if plan.fly_on == "estimate":
        wanted += ["gps", "barometer"]
    for name in wanted:
        if name not in names:
            chosen.append(_NAV[name]())
            names.add(name)
    if drone.camera is not None and "camera" not in names and (
            "camera" in drone.sensors or plan.dataset_dir is not None
            or any(tk.sensor == "camera" for tk in plan.tasks)):
        chosen.append(Camera.from_blueprint(drone, conditions=plan.conditions))
    if not unread_camera and not any(tk.sensor == "camera" for tk in plan.tasks):
        chosen = [sn for sn in chosen if not isinstance(sn, Camera)]
    return SensorSuite(chosen)


class DroneData:
    """One drone's view of the shared MjData: ``qpos qvel ctrl act`` are numpy
    views of its free joint and its rotors; ``ncon`` counts only the contacts
    that touch its body; ``time`` is the flight's clock. The components read
    these names, so they run unchanged on a drone among others."""

    def __init__(self, model, data, prefix: str, n_rotors: int):
        self._model, self._data = model, data
        j = model.joint(f"{prefix}drone")
        qa, va = int(model.jnt_qposadr[j.id]), int(model.jnt_dofadr[j.id])
        self.qpos, self.qvel = data.qpos[qa:qa + 7], data.qvel[va:va + 6]
        a0 = model.actuator(f"{prefix}rotor0").id
        self.ctrl = data.ctrl[a0:a0 + n_rotors]
        ad = int(model.actuator_actadr[a0])
        self.act = data.act[ad:ad + n_rotors]
        self.body = model.body(f"{prefix}drone").id
        self.xfrc = data.xfrc_applied[self.body]

    @property
    def time(self) -> float:
        return self._data.time

    @property
    def ncon(self) -> int:
        d = self._data
        if d.ncon == 0:
            return 0
        bodies = self._model.geom_bodyid[d.contact.geom[:d.ncon]]
        return int(np.count_nonzero((bodies == self.body).any(axis=1)))


class Slot:
    """Where one drone sits in its flight's model: the model, the shared MjData,
    its index and name, the prefix of its MuJoCo names and its sensors."""

    __slots__ = ("model", "data", "index", "name", "prefix", "suite", "alone")

    def __init__(self, model, data, index: int, name: str, prefix: str, suite, alone: bool):
        self.model, self.data, self.index, self.name = model, data, index, name
        self.prefix, self.suite, self.alone = prefix, suite, alone


class Flight:
    """A flight of 1..N drones being flown: the one MuJoCo ``model`` and MjData
    (``data``), and one ``Run`` per drone (``runs``, in the order of ``plans``).

    ``names`` None: a single flight (one plan; the drone is ``drone``, nothing
    prefixed); else each drone's name, which prefixes its MuJoCo names, and
    ``pads``: where each stands, (x, y)."""

    def __init__(self, plans, missions, names=None, pads=None):
        slots = place(plans, names, pads)
        self.model, self.data = slots[0].model, slots[0].data
        self.runs = [Run(plan, m, m.subscribers, m.probes, slot=slot)
                     for plan, m, slot in zip(plans, missions, slots)]


def place(plans, names=None, pads=None) -> list[Slot]:
    """The slots of the drones of ``plans`` in their flight's one model and MjData
    (see ``Flight``)."""
    fleet = names is not None
    names = list(names) if fleet else ["drone"]
    prefixes = [f"{name}/" for name in names] if fleet else [""]
    pads = [tuple(p) for p in pads] if pads is not None else [(0.0, 0.0)] * len(plans)
    suites = [sensor_suite(p, unread_camera=not fleet) for p in plans]
    model = flight_model(plans, prefixes, pads, suites, "fleet" if fleet else None)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return [Slot(model, data, i, name, prefix, suite, len(plans) == 1)
            for i, (name, prefix, suite) in enumerate(zip(names, prefixes, suites))]


def flight_model(plans, prefixes, pads, suites, name=None) -> mujoco.MjModel:
    """The compiled model of a flight: the world of ``plans[0]`` (the drones share
    it, its air and its physics step) and every drone on its pad with its sensors,
    compiled once per world and drones (``airframe.model_cache``). Arms and
    propellers only show in cameras and rays: they are left out when no sensor of
    the flight looks (``add_drone(visual=False)``)."""
    p0 = plans[0]
    visual = any(not isinstance(sn, BLIND) for suite in suites for sn in suite.sensors)

    def add_drones(spec) -> None:
        for plan, prefix, pad, suite in zip(plans, prefixes, pads, suites):
            add_drone(spec, plan.drone, rho=plan.atmosphere.density, prefix=prefix, pos=pad,
                      visual=visual)
            suite.add_to_spec(spec, f"{prefix}drone")
        if p0.actors:                  # people and cars walking, markers (a single flight's)
            ActorSet(p0.actors).add_to_spec(spec)

    return model_cache.compiled(name or p0.drone.name, p0.world, add_drones,
                                physics_dt=p0.physics_dt, rho=p0.atmosphere.density)


class Run:
    """One drone of a flight being flown: the flight's MuJoCo model, its data
    (the MjData itself when the drone is alone, else its ``DroneData`` view;
    ``shared``: the flight's MjData), the vehicle's state, the event log and the
    clocked components in stepping order. It is also what a user component's
    ``bind(run)`` receives. ``slot`` None: a flight of its own (its model built here)."""

    def __init__(self, plan: FlightPlan, mission=None, subscribers=(), probes=(), *,
                 slot: Slot | None = None):
        slot = slot if slot is not None else place([plan])[0]
        self.plan, self.mission = plan, mission
        drone = plan.drone
        self.suite, self.model, self.shared = slot.suite, slot.model, slot.data
        view = DroneData(slot.model, slot.data, slot.prefix, drone.airframe.rotor_count)
        self.data = slot.data if slot.alone else view
        #: the rotors' filtered thrusts and the drone body's applied force (RotorDrag)
        self.rotor_views = (view.act, view.xfrc)
        self.body = view.body
        self.events = EventLog()
        self.vehicle = st = VehicleState(slot.name, slot.index, e_usable=drone.battery.energy_j)
        q = view.qpos
        st.home = (float(q[0]), float(q[1]), float(q[2]))
        self.suite.bind(slot.model, slot.data, seed_sequence(plan.seed, "sensors"),
                        world=plan.world, battery=lambda: st.battery_remaining)
        self.controller = parts.controller(plan)
        self.meter = parts.meter(plan)
        self.actors = ActorSet(plan.actors) if plan.actors else None
        if self.actors is not None:
            self.actors.bind(self.model)       # their geoms: added by flight_model
        for sensor in self.suite:
            if hasattr(sensor, "bind_actors"):
                sensor.bind_actors(self.actors)        # None: no actors in this flight
        self.components = self._components(plan, subscribers, probes)
        # the task scheduler reads the camera, which renders the whole MjData
        self.scheduler.data = slot.data
        #: s: when this drone's flight ended (set by the loop)
        self.t_end = 0.0

    def _components(self, plan, subscribers, probes) -> list:
        drone, st, d = plan.drone, self.vehicle, self.data
        n_rot = drone.airframe.rotor_count
        accel = parts.trajectory_accel(plan, self.controller)
        self.stages = StageMachine(st, copy.deepcopy(plan.pilot), self.events, d, accel=accel,
                                   climb_speed=plan.climb_speed, descent_speed=plan.descent_speed,
                                   return_home=plan.return_home,
                                   top_speed=top_speed(drone, plan.atmosphere.density))
        recorder = DatasetRecorder(plan.dataset_period_s) if plan.dataset_dir is not None else None
        seeds = seed_sequence(plan.seed, "tasks").spawn(len(plan.tasks)) if plan.tasks else []
        self.scheduler = TaskScheduler(st, plan.tasks, seeds, self.suite, d, recorder=recorder,
                                       computer=plan.onboard_device)
        tasks = self.scheduler if self.scheduler.runners else None
        self.traffic = Traffic()
        self.book = FlightBook(st, self.events, plan.ctrl_dt)
        self.view = RunView(plan.drone, self.meter, mission=self.mission)
        self.hub = ProbeHub(list(probes) + [TaskProbe(tk.name) for tk in plan.tasks], subscribers)
        self.hub.bind(self.view)
        self.probing = ProbeStep(self.hub, self.view, st, self.book, self.traffic, self.suite, tasks,
                                 memory_utilization(plan.tasks, plan.onboard_device))
        rows = int(plan.t_end * plan.telemetry_hz) + 16     # the first chunk at most this big
        estimator = NavEstimator() if plan.fly_on == "estimate" else None
        self.telemetry = TelemetryRecorder(rows, n_rot, self.meter, d, self.suite, estimator)
        slots: dict[str, list[Clocked]] = {"sensing": [Sensing(self.suite, d)]}
        if self.scheduler.consumers:
            slots["tasks"] = [self.scheduler]
        if estimator is not None:
            slots["navigation"] = [Navigation(st, estimator, self.suite)]
        slots["stages"], slots["control"] = [self.stages], [Control(st, self.controller, d, n_rot)]
        if plan.wind is not None:
            rng = seed_sequence(plan.seed, "wind")
            slots["wind"] = [WindStep(plan.wind, st, self.model, np.random.default_rng(rng),
                                      plan.ctrl_dt)]
        if drone.rotor.blade_drag > 0.0:
            slots["rotor_drag"] = [RotorDrag(drone, st, *self.rotor_views, plan.atmosphere.density)]
        slots["heartbeats"] = [Heartbeats(self.traffic, drone.radio)]
        slots["energy"] = [EnergyIntegrator(st, self.meter, d, self.traffic, tasks,
                                            energy_hz=plan.energy_hz, n_rotors=n_rot)]
        slots["book"], slots["probes"] = [self.book], [self.probing]
        slots["telemetry"] = [TelemetryStep(self.telemetry, st, d, plan.telemetry_hz)]
        for c in plan.components:
            c.bind(self)
        slots["components"] = list(plan.components)
        self.policies = [copy.copy(p) for p in plan.policies]   # per-flight state on the copy
        for p in self.policies:
            p.bind(self)
        slots["policies"] = list(self.policies)
        if plan.max_wall_s is not None:
            guard = WallClockGuard(plan.max_wall_s)
            guard.bind(self)
            slots["wall_clock"] = [guard]
        slots["end"] = [EndConditions(
            st, self.events, self.stages, t_end=plan.t_end, dt=plan.ctrl_dt,
            timed=not isinstance(plan.until, str), use_reserve=plan.use_reserve,
            reserve_j=drone.battery.reserve_fraction * st.e_usable, energy_hz=plan.energy_hz)]
        return steps.ordered(slots)          # the stepping order: mission/steps.py STEP_ORDER

    # -- for user components ---------------------------------------------------
    def event(self, t: float, kind: str, **info) -> None:
        """Log an event of the flight (it appears in ``result.events``)."""
        self.events.add(t, kind, **info)

    def stop(self, reason: str) -> None:
        """End the flight after this tick; ``reason`` becomes ``result.end_reason``."""
        self.vehicle.end_reason = str(reason)
