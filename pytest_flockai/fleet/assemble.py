"""Build a fleet's flight: ONE MuJoCo model holding the world and every drone,
one MjData (one simulated clock), and per drone the same clocked components a
single flight has (``mission.assemble.Run``), each bound to that drone's slice
of the shared MjData (``DroneData``)."""

from __future__ import annotations

import mujoco
import numpy as np

from ..airframe.model import add_drone, world_spec
from ..control.controller import CascadedController
from ..energy.factory import flight_energy_model
from ..energy.model import Meter
from ..mission.assemble import Run, sensor_suite
from ..mission.plan import seed_sequence
from ..mission.state import EventLog, VehicleState
from ..ml.events import SharedGround
from ..sensors import GPS, IMU, Barometer, BatterySensor, Camera, Compass, SensorSuite

#: sensors that read the drone's own state only: they never look at a geom
BLIND = (IMU, GPS, Barometer, Compass, BatterySensor)


class DroneData:
    """One drone's view of the shared MjData: ``qpos qvel ctrl act`` are numpy
    views of its free joint and its rotors; ``ncon`` counts only the contacts
    that touch its body; ``time`` is the fleet's clock. The components of a
    single flight read these names, so they run unchanged on a drone of a fleet."""

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

    def flipped(self) -> bool:
        """Upside down (the body's z axis points below the horizon)."""
        return self._data.xmat[self.body][8] < 0.0


class DroneRun(Run):
    """One drone of a fleet: a ``Run`` whose model and data are the fleet's
    (``data`` is its ``DroneData`` view; ``shared`` the fleet's MjData)."""

    def __init__(self, plan, mission, model, shared, view: DroneData, index: int, name: str,
                 suite, subscribers=(), probes=()):
        self.plan, self.mission = plan, mission
        drone = plan.drone
        self.suite = suite
        self.model, self.data, self.shared = model, view, shared
        self.events = EventLog()
        self.vehicle = st = VehicleState(name, index, e_usable=drone.battery.energy_j)
        q = view.qpos
        st.home = (float(q[0]), float(q[1]), float(q[2]))
        self.suite.bind(model, shared, seed_sequence(plan.seed, "sensors"), world=plan.world,
                        battery=lambda: st.battery_remaining)
        rho = plan.atmosphere.density
        self.controller = CascadedController(drone, plan.ctrl_dt, rho=rho)
        self.meter = Meter(flight_energy_model(
            drone.energy, extra_sensors=list(drone.extra_sensors) + list(plan.sensors),
            device=plan.onboard_device, blueprint_device=drone.device), drone, rho=rho)
        self.components = self._components(plan, subscribers, probes)
        # the task scheduler reads the camera, which renders the whole MjData
        self.scheduler.data = shared


def _suite(plan) -> SensorSuite:
    """The drone's sensors: the single flight's, less the blueprint's camera when no
    task of the drone reads it (it still draws power through the energy model)."""
    sensors = sensor_suite(plan).sensors
    if not any(tk.sensor == "camera" for tk in plan.tasks):
        sensors = [sn for sn in sensors if not isinstance(sn, Camera)]
    return SensorSuite(sensors)


def share_ground(runs, shared_link: bool) -> SharedGround:
    """One ground station for the remote tasks of every drone (``ml.events.SharedGround``)."""
    ground = SharedGround(shared_link)
    for i, r in enumerate(runs):
        for runner in r.scheduler.runners:
            if runner.task.execution == "remote":
                runner.share(ground, i)
    return ground


def prefix_of(name: str) -> str:
    return f"{name}/"


def build(plans, missions, names, pads, world, probes_of) -> tuple:
    """The fleet's model, its MjData and one ``DroneRun`` per drone."""
    p0 = plans[0]
    spec = world_spec("fleet", world, physics_dt=p0.physics_dt, rho=p0.atmosphere.density)
    suites = [_suite(plan) for plan in plans]
    # arms and propellers only show in cameras and rays: left out when nothing looks
    visual = any(not isinstance(sn, BLIND) for suite in suites for sn in suite.sensors)
    for plan, name, pad, suite in zip(plans, names, pads, suites):
        add_drone(spec, plan.drone, rho=plan.atmosphere.density, prefix=prefix_of(name), pos=pad,
                  visual=visual)
        suite.add_to_spec(spec, f"{prefix_of(name)}drone")
    model = spec.compile()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    runs = []
    for i, (plan, m, name, suite) in enumerate(zip(plans, missions, names, suites)):
        view = DroneData(model, data, prefix_of(name), plan.drone.airframe.rotor_count)
        runs.append(DroneRun(plan, m, model, data, view, i, name, suite,
                             m.subscribers, probes_of(m)))
    return model, data, runs
