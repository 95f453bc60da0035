"""A Mission resolved into a frozen flight plan: every check, before anything flies.

``resolve(mission)`` validates the mission as a whole (the drone's blueprint,
the physics and control rates, the tasks against the drone's sensors and
computer, the user's components) and derives what the loop needs: time
steps, the end time, the on-board computer. A bad input raises a
``ConfigError`` naming the field, the value and what is allowed, when the
Mission is built. The Mission's own fields are frozen and checked once (in
``Mission.__post_init__``, with the ``check_*`` functions here); the drone is
an object of its own that may be edited after, so ``Mission.run()`` resolves
again and the checks that read the drone (its blueprint, rates, camera, the
tasks' sensors and computer, the time limits) run again then.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from numbers import Real

import numpy as np

from .. import _check, limits
from ..airframe.drone import Drone
from ..clock import Clocked
from ..compute import runtimes as _rt
from ..control.pilots import Pilot
from ..errors import ConfigError
from ..ml import Task
from ..policy import Policy, register_kpis
from ..probes.builtin import BUILTIN
from ..sensors import Sensor
from ..world.atmosphere import Atmosphere
from ..world.wind import Wind

UNTIL = ("landed", "battery_depleted", "battery_reserve")
NAV_SENSORS = ("battery", "barometer", "compass", "gps", "imu", "rangefinder")
#: fixed spawn keys of the mission seed, one per random component
SEEDS = {"wind": 0, "sensors": 1, "tasks": 2, "link": 3, "world": 4, "probes": 5}


def seed_sequence(seed: int, component: str) -> np.random.SeedSequence:
    """The SeedSequence of one component of a mission (fixed spawn keys)."""
    return np.random.SeedSequence(seed, spawn_key=(SEEDS[component],))


@dataclass(frozen=True)
class FlightPlan:
    drone: Drone
    pilot: Pilot
    world: object
    tasks: tuple
    sensors: tuple            # the mission's sensors (the drone's own are on the drone)
    components: tuple         # the user's clocked components
    wind: Wind | None
    seed: int
    until: object
    t_end: float              # s: when the loop stops at the latest
    physics_dt: float
    substeps: int
    ctrl_dt: float
    telemetry_hz: float
    energy_hz: float
    climb_speed: float
    descent_speed: float
    return_home: bool
    fly_on: str
    dataset_dir: object
    dataset_period_s: float
    onboard_device: object    # compute.Device the on-board tasks run on (or the drone's), or None
    conditions: object = None  # sensors.Conditions for the blueprint's camera
    atmosphere: Atmosphere = Atmosphere()   # the air: density for thrust, drag and power
    max_wall_s: float | None = None  # s of host time before the flight is stopped
    policies: tuple = ()      # fa.Policy objects (copied per flight)
    actors: tuple = ()        # fa.actors.Person / Car moving through the world

    @property
    def use_reserve(self) -> bool:
        return self.until == "battery_reserve"


def check_until(until):
    if isinstance(until, str):
        return _check.choice("until", until, UNTIL, where="Mission")
    if isinstance(until, Real) and not isinstance(until, bool):
        return _check.positive("until", until, where="Mission")
    raise ConfigError(f"Mission: until = {until!r} is not allowed; allowed: "
                      f"{', '.join(map(repr, UNTIL))} or a number of seconds > 0")


def check_time_limits(until, max_time_s: float, telemetry_hz: float, probes=()) -> float:
    """The end time of the flight, within ``limits`` (ConfigError naming the field above one)."""
    limits.check_at_most("max_time_s", max_time_s, "MAX_TIME_S", where="Mission", unit=" s")
    if not isinstance(until, str) and until > max_time_s:
        raise ConfigError(f"Mission: until = {until:g} s is above max_time_s = {max_time_s:g} s; "
                          f"allowed: a number of seconds <= max_time_s (pass Mission(max_time_s=...) "
                          f"to fly longer, up to limits.MAX_TIME_S = {limits.MAX_TIME_S:g} s)")
    t_end = float(until) if not isinstance(until, str) else max_time_s
    limits.check_at_most("telemetry rows (until or max_time_s x telemetry_hz)", t_end * telemetry_hz,
                         "MAX_TELEMETRY_ROWS", where="Mission",
                         how=f"lower telemetry_hz = {telemetry_hz:g} or the flight's {t_end:g} s")
    for p in probes:
        if getattr(p, "enabled", True):
            limits.check_at_most(f"probe {p.name!r} samples (flight time / period_s = "
                                 f"{t_end:g} s / {p.period_s:g} s)", t_end / p.period_s,
                                 "MAX_PROBE_SAMPLES", where="Mission",
                                 how="give the probe a longer period_s")
    return t_end


def check_tasks(tasks, drone, sensors) -> tuple:
    try:
        tasks = tuple(tasks or ())
    except TypeError:
        raise ConfigError(f"Mission: tasks = {tasks!r} is not a list of Task objects") from None
    names = set()
    reserved = {cls.name for cls in BUILTIN}
    extra = {sn.name for sn in list(drone.extra_sensors) + list(sensors)}
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
        _check_task_sensor(tk, drone, extra)
    onboard = {tk.device.name if tk.device is not None else drone.device
               for tk in tasks if tk.execution == "onboard"}
    if len(onboard) > 1:
        raise ConfigError(f"Mission: on-board tasks run on different computers "
                          f"({', '.join(sorted(onboard))}); the tasks of one drone share one "
                          f"computer: give them the same device (or none: the drone's own)")
    if "none" in onboard:
        tk = next(tk for tk in tasks if tk.execution == "onboard")
        raise ConfigError(f"task {tk.name!r} runs on the drone's on-board computer, and "
                          f"{drone.name} has none ([compute] device = \"none\"); give the task "
                          f"device=... (the computer is then carried and powered) or "
                          f"execution='remote'")
    return tasks


def _check_task_sensor(tk, drone, extra):
    if tk.sensor == "camera":
        if drone.camera is None and "camera" not in extra:
            raise ConfigError(f"task {tk.name!r} reads sensor 'camera', but {drone.name} has no "
                              f"[camera] section; add one to the blueprint or add a camera "
                              f"sensor (drone.add_sensor(fa.sensors.ReplayCamera(...)))")
    elif tk.sensor not in extra and tk.sensor not in NAV_SENSORS:
        raise ConfigError(f"task {tk.name!r} reads sensor {tk.sensor!r}, which is not on "
                          f"{drone.name}; add it with drone.add_sensor(...) or "
                          f"Mission(sensors=[...]); built in: camera, {', '.join(NAV_SENSORS)}")


def check_sensors(sensors) -> tuple:
    try:
        sensors = tuple(sensors or ())
    except TypeError:
        raise ConfigError(f"Mission: sensors = {sensors!r} is not a list of Sensor objects") from None
    for i, sn in enumerate(sensors):
        if not isinstance(sn, Sensor):
            raise ConfigError(f"Mission: sensors[{i}] = {sn!r} is not a Sensor")
    return sensors


def check_components(components) -> tuple:
    try:
        components = tuple(components or ())
    except TypeError:
        raise ConfigError(f"Mission: components = {components!r} is not a list of "
                          f"fa.Clocked components") from None
    for i, c in enumerate(components):
        if not isinstance(c, Clocked):
            raise ConfigError(f"Mission: components[{i}] = {c!r} is not a Clocked component; "
                              f"subclass fa.Clocked and implement step(t)")
    return components


def check_policies(policies, mission) -> tuple:
    """The policies as a tuple: each a ``Policy`` with its own name, checked against
    the mission (the tasks, signals and actors it names); their KPIs registered."""
    try:
        policies = tuple(policies or ())
    except TypeError:
        raise ConfigError(f"Mission: policies = {policies!r} is not a list of fa.Policy") from None
    names: set = set()
    for i, p in enumerate(policies):
        if not isinstance(p, Policy):
            raise ConfigError(f"Mission: policies[{i}] = {p!r} is not a Policy; use fa.policy.Rule, "
                              f"Follow, SearchThenOrbit or subclass fa.Policy")
        _check.overrides(p, Policy, "decide", "(t, drone)")    # one that skipped Policy.__init__
        if p.name in names:
            raise ConfigError(f"Mission: two policies are named {p.name!r}; give them name=... "
                              f"(policy names prefix their KPIs)")
        names.add(p.name)
        p.check(mission)
        register_kpis(p.name, p.modes)
    return policies


def onboard_device(tasks, drone):
    """The computer the on-board tasks run on: the one they name, else the drone's own."""
    for tk in tasks:
        if tk.execution == "onboard" and tk.device is not None:
            return tk.device
    if drone.computer is None:
        return None
    return with_defaults(drone.computer, drone)


def with_defaults(dev, drone):
    """The drone's computer carrying the blueprint's / ``fa.drone()``'s default runtime,
    precision, target and threads for its tasks (checked against the computer now)."""
    d = {k: getattr(drone, k, None) for k in ("runtime", "precision", "target", "threads")}
    if all(v is None for v in d.values()):
        return dev
    _rt.resolve(dev, **d, where=f"{drone.name} [compute]")
    return replace(dev, defaults=tuple((k, v) for k, v in d.items() if v is not None))


def computers(tasks, drone) -> list[dict]:
    """The on-board computers a flight carries, for the scenario: the blueprint's,
    and the one an on-board task names when it is another (added and powered)."""
    out = [] if drone.device == "none" else [{"name": drone.device, "source": "blueprint"}]
    for tk in tasks or ():
        dev = getattr(tk, "device", None)
        if getattr(tk, "execution", None) == "onboard" and dev is not None and \
                dev.name != drone.device and all(c["name"] != dev.name for c in out):
            out.append({"name": dev.name, "source": f"added by task {tk.name!r}"})
    return out


def resolve(m) -> FlightPlan:
    """The flight plan of the (checked, frozen) Mission ``m``; ConfigError where the
    drone, as it is now, does not fit the mission."""
    drone = m.drone
    atmosphere = Atmosphere.coerce(getattr(m, "atmosphere", None))
    drone.check(rho=atmosphere.density)
    sim = drone.sim
    if sim.physics_hz < sim.control_hz:
        raise ConfigError(f"{drone.name} [sim]: physics_hz = {sim.physics_hz:g} must be >= "
                          f"control_hz = {sim.control_hz:g}")
    substeps = max(1, int(round(sim.physics_hz / sim.control_hz)))
    physics_dt = 1.0 / sim.physics_hz
    tasks = check_tasks(m.tasks, drone, m.sensors)     # against the drone as it is now
    until = m.until
    t_end = check_time_limits(until, m.max_time_s, m.telemetry_hz, m.probes)
    if m.dataset_dir is not None and drone.camera is None:
        raise ConfigError(f"Mission: dataset_dir = {str(m.dataset_dir)!r} needs a camera, and "
                          f"{drone.name} has no [camera] section")
    return FlightPlan(
        drone=drone, pilot=m.pilot, world=m.world, tasks=tasks, sensors=tuple(m.sensors),
        components=tuple(m.components), wind=m.wind, seed=m.seed,
        until=until, t_end=t_end, physics_dt=physics_dt, substeps=substeps,
        ctrl_dt=physics_dt * substeps, telemetry_hz=m.telemetry_hz, energy_hz=m.energy_hz,
        climb_speed=m.climb_speed, descent_speed=m.descent_speed, return_home=m.return_home,
        fly_on=m.fly_on, dataset_dir=m.dataset_dir, dataset_period_s=m.dataset_period_s,
        onboard_device=onboard_device(tasks, drone), conditions=m.conditions, atmosphere=atmosphere,
        max_wall_s=m.max_wall_s, policies=tuple(m.policies), actors=tuple(m.actors))
