"""What the components of one flight share, explicitly: the vehicle's state
this tick and the event log.

``VehicleState`` is written by the component that owns each field and read by
the others (see the field notes); the loop fills ``t q v speed`` at the start
of every control tick. One ``VehicleState`` per drone: nothing in the loop
assumes there is exactly one.
"""

from __future__ import annotations

import math

from ..phases import Phase


class VehicleState:
    """One drone's state during a flight."""

    __slots__ = (
        "name", "index",
        # the loop, every tick: MuJoCo qpos/qvel as lists, speed (m/s)
        "q", "v", "speed",
        # navigation: what the pilot and controller fly on (estimates or truth)
        "qc", "vc",
        # stage machine: the stage (control.stages) and the setpoint
        # [x y z vx vy vz ax ay az yaw]; t_land when it landed
        "stage", "sp", "t_land", "home",
        # controller: False once the motors are off on the ground
        "airborne",
        # wind: the air velocity this tick (m/s)
        "w",
        # energy integrator: power of the last interval (W), energy used (J), usable energy
        "power", "energy_j", "e_usable", "battery_remaining",
        # battery circuit: terminal voltage (V); True once it fell below the cut-off
        "battery_v", "battery_cutoff",
        # flight book: the phase now
        "phase",
        # end: why the flight ended (None while flying), whether it crashed
        "end_reason", "crashed",
    )

    def __init__(self, name: str = "drone", index: int = 0, *, e_usable: float = math.inf):
        self.name, self.index = name, index
        self.q: list = []
        self.v: list = []
        self.speed = 0.0
        self.qc: list = []
        self.vc: list = []
        self.stage = 0
        self.sp = [0.0] * 10
        self.t_land = None
        self.home = (0.0, 0.0, 0.0)
        self.airborne = True
        self.w = (0.0, 0.0, 0.0)
        self.power = 0.0
        self.energy_j = 0.0
        self.e_usable = e_usable
        self.battery_remaining = 1.0
        self.battery_v = 0.0
        self.battery_cutoff = False
        self.phase = int(Phase.TAKEOFF)
        self.end_reason: str | None = None
        self.crashed = False


class EventLog:
    """Events of a flight (stage and phase changes, crash, battery...), in order."""

    def __init__(self):
        self.items: list[dict] = []

    def add(self, t: float, kind: str, **info) -> None:
        self.items.append({"t": round(float(t), 6), "kind": kind, **info})
