"""The stepping order of one drone's clocked components, written once.

``assemble.Run`` builds each drone's component list in this order (a step a
flight does not need is left out: no tasks, no wind, no ``max_wall_s``...), the
flight loop (``loop.fly``) steps the components that are due in the order of
that list each tick, and the docs print this table (``docs/gen.py``:
``step_order``). The order is a decision: the estimate before the stage
machine that flies on it, the controller after the setpoint it follows, the
wind before the rotor drag in that air, the energy after this tick's thrust
and traffic, the user's components after the built-in ones, the end
conditions last.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Step:
    """One step of a drone's tick: the slot ``assemble.Run`` fills (``key``), the
    component in it, its module, what it does and when it is due."""

    key: str
    component: str
    module: str
    does: str
    clock: str


STEP_ORDER: tuple[Step, ...] = (
    Step("sensing", "Sensing", "sensors/base.py", "reads the sensors that are due",
         "each sensor's rate"),
    Step("tasks", "TaskScheduler", "ml/scheduler.py",
         "ML tasks that read a sensor, and the dataset recorder (when there are any)",
         "each task's period, while surveying"),
    Step("navigation", "Navigation", "control/clocked.py",
         "estimates to fly on (`fly_on=\"estimate\"`)", "every tick"),
    Step("stages", "StageMachine", "control/stages.py",
         "take-off, the pilot's plan, return, landing; the setpoint", "every tick"),
    Step("control", "Control", "control/clocked.py",
         "the cascaded controller: rotor thrust commands", "every tick"),
    Step("wind", "WindStep", "world/wind.py", "the air this tick (`opt.wind`), with a wind",
         "every tick"),
    Step("rotor_drag", "RotorDrag", "airframe/rotor_drag.py",
         "rotor drag (H-force) in this tick's air, when `blade_drag > 0`", "every tick"),
    Step("heartbeats", "Heartbeats", "comm/traffic.py", "the radio's heartbeat traffic",
         "`heartbeat_period_s`"),
    Step("energy", "EnergyIntegrator", "energy/integrator.py",
         "power, energy used, battery voltage (the only place energy is summed)", "`energy_hz`"),
    Step("book", "FlightBook", "mission/book.py", "phases, distance, top speed, tracking error",
         "50 Hz"),
    Step("probes", "ProbeStep", "mission/probing.py", "the probes that are due",
         "each probe's period"),
    Step("telemetry", "TelemetryStep", "probes/telemetry.py", "one telemetry row",
         "`telemetry_hz`"),
    Step("components", "your components", "`Mission(components=[...])`",
         "after the built-in ones", "yours"),
    Step("policies", "your policies", "`Mission(policies=[...])`",
         "decide from what the drone knows (`fa.policy`)", "each policy's `period_s`"),
    Step("wall_clock", "WallClockGuard", "mission/ending.py",
         "stops a runaway flight (`max_wall_s`)", "every tick"),
    Step("end", "EndConditions", "mission/ending.py", "battery depleted, reserve, time limit",
         "`energy_hz`, each tick near the end"),
)

#: the slot names, in stepping order
STEP_KEYS: tuple[str, ...] = tuple(s.key for s in STEP_ORDER)


def ordered(slots: dict) -> list:
    """The components of ``slots`` ({key: [component, ...]}) in ``STEP_ORDER``;
    ValueError for a key the table does not have (a step added without its row)."""
    unknown = set(slots) - set(STEP_KEYS)
    if unknown:
        raise ValueError(f"components in slots {sorted(unknown)} have no row in STEP_ORDER; "
                         f"add one (mission/steps.py) where they step")
    return [c for key in STEP_KEYS for c in slots.get(key, ())]
