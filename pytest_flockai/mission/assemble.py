"""Build one flight from its plan: the MuJoCo model, the vehicle's state and
its clocked components, in the order the loop steps them each tick."""

from __future__ import annotations

import copy

import mujoco
import numpy as np

from ..airframe.model import build_spec
from ..airframe.rotor_drag import RotorDrag
from ..clock import Clocked
from ..comm.traffic import Heartbeats, Traffic
from ..control.controller import CascadedController
from ..control.estimator import NavEstimator
from ..control.stages import StageMachine
from ..control.steps import Control, Navigation
from ..control.trajectory import accel_limit
from ..energy.factory import flight_energy_model
from ..energy.integrator import EnergyIntegrator
from ..energy.model import Meter
from ..ml.scheduler import DatasetRecorder, TaskScheduler, memory_utilization
from ..probes.builtin import TaskProbe
from ..probes.hub import ProbeHub, RunView
from ..probes.telemetry import TelemetryRecorder, TelemetryStep
from ..sensors import (IMU, GPS, Barometer, BatterySensor, Camera, Compass, Rangefinder,
                       SensorSuite)
from ..sensors.base import Sensing
from ..world.wind import WindStep
from .book import FlightBook
from .ending import EndConditions, WallClockGuard
from .plan import FlightPlan, seed_sequence
from .probing import ProbeStep
from .state import EventLog, VehicleState

_NAV = {"gps": GPS, "barometer": Barometer, "imu": IMU, "compass": Compass,
        "rangefinder": Rangefinder, "battery": BatterySensor}


def sensor_suite(plan: FlightPlan) -> SensorSuite:
    """The sensors read in this flight: the ones added to the drone or the
    mission, GPS and barometer when flying on estimates, and the blueprint's
    camera (rendered only when something asks for a frame). The blueprint's
    other sensors draw power through the energy model but are not read."""
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
    return SensorSuite(chosen)


class Run:
    """One flight being flown: its MuJoCo model and data, the vehicle's state,
    the event log and the clocked components in stepping order. It is also
    what a user component's ``bind(run)`` receives."""

    def __init__(self, plan: FlightPlan, mission=None, subscribers=(), probes=()):
        self.plan, self.mission = plan, mission
        drone = plan.drone
        self.suite = sensor_suite(plan)
        rho = plan.atmosphere.density
        spec = build_spec(drone, plan.world, physics_dt=plan.physics_dt, rho=rho)
        self.suite.add_to_spec(spec, "drone")
        self.model = spec.compile()
        self.data = mujoco.MjData(self.model)
        mujoco.mj_forward(self.model, self.data)
        a0 = self.model.actuator("rotor0").id
        ad, n = int(self.model.actuator_actadr[a0]), drone.airframe.rotor_count
        #: the rotors' filtered thrusts and the drone body's applied force (RotorDrag)
        self.rotor_views = (self.data.act[ad:ad + n],
                            self.data.xfrc_applied[self.model.body("drone").id])
        self.events = EventLog()
        self.vehicle = st = VehicleState("drone", 0, e_usable=drone.battery.energy_j)
        st.home = (0.0, 0.0, float(self.data.qpos[2]))
        self.suite.bind(self.model, self.data, seed_sequence(plan.seed, "sensors"), world=plan.world,
                        battery=lambda: st.battery_remaining)
        self.controller = CascadedController(drone, plan.ctrl_dt, rho=rho)
        self.meter = Meter(flight_energy_model(
            drone.energy, extra_sensors=list(drone.extra_sensors) + list(plan.sensors),
            device=plan.onboard_device, blueprint_device=drone.device), drone, rho=rho)
        self.components = self._components(plan, subscribers, probes)

    def _components(self, plan, subscribers, probes) -> list:
        drone, st, d = plan.drone, self.vehicle, self.data
        n_rot = drone.airframe.rotor_count
        accel = accel_limit(drone.thrust_to_weight_at(plan.atmosphere.density),
                            self.controller.k_vel)
        self.stages = StageMachine(st, copy.deepcopy(plan.pilot), self.events, d, accel=accel,
                                   climb_speed=plan.climb_speed, descent_speed=plan.descent_speed,
                                   return_home=plan.return_home)
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
        comps: list[Clocked] = [Sensing(self.suite, d)]
        if self.scheduler.consumers:
            comps.append(self.scheduler)
        if estimator is not None:
            comps.append(Navigation(st, estimator, self.suite))
        comps += [self.stages, Control(st, self.controller, d, n_rot)]
        if plan.wind is not None:
            rng = seed_sequence(plan.seed, "wind")
            comps.append(WindStep(plan.wind, st, self.model, np.random.default_rng(rng), plan.ctrl_dt))
        if drone.rotor.blade_drag > 0.0:              # after the wind: this tick's air
            comps.append(RotorDrag(drone, st, *self.rotor_views, plan.atmosphere.density))
        comps += [Heartbeats(self.traffic, drone.radio),
                  EnergyIntegrator(st, self.meter, d, self.traffic, tasks,
                                   energy_hz=plan.energy_hz, n_rotors=n_rot),
                  self.book, self.probing,
                  TelemetryStep(self.telemetry, st, d, plan.telemetry_hz)]
        for c in plan.components:
            c.bind(self)
            comps.append(c)
        if plan.max_wall_s is not None:
            guard = WallClockGuard(plan.max_wall_s)
            guard.bind(self)
            comps.append(guard)
        comps.append(EndConditions(
            st, self.events, self.stages, t_end=plan.t_end, dt=plan.ctrl_dt,
            timed=not isinstance(plan.until, str), use_reserve=plan.use_reserve,
            reserve_j=drone.battery.reserve_fraction * st.e_usable, energy_hz=plan.energy_hz))
        return comps

    # -- for user components ---------------------------------------------------
    def event(self, t: float, kind: str, **info) -> None:
        """Log an event of the flight (it appears in ``result.events``)."""
        self.events.add(t, kind, **info)

    def stop(self, reason: str) -> None:
        """End the flight after this tick; ``reason`` becomes ``result.end_reason``."""
        self.vehicle.end_reason = str(reason)
