"""The parts of one drone's flight built from its ``FlightPlan``, one factory each:
the controller, the energy model and its meter, the trajectories' acceleration
limit. Every flight (a single Mission, each drone of a fleet) and the batched
backend take them from here, so a part is wired once."""

from __future__ import annotations

from ..control.controller import CascadedController
from ..energy.factory import flight_energy_model
from ..energy.tree import Meter
from ..physics import G
from .plan import FlightPlan

#: m/s^2: the trajectories' acceleration limit at most (a gentle survey drone)
MAX_ACCEL = 2.5


def controller(plan: FlightPlan) -> CascadedController:
    """The drone's cascaded controller at the plan's control rate, in the plan's air."""
    return CascadedController(plan.drone, plan.ctrl_dt, rho=plan.atmosphere.density)


def energy_model(plan: FlightPlan):
    """The drone's energy model for this flight: the blueprint's, plus the sensors
    added to the drone or the mission and the computer the on-board tasks run on
    (``energy.factory.flight_energy_model``)."""
    drone = plan.drone
    return flight_energy_model(drone.energy,
                               extra_sensors=list(drone.extra_sensors) + list(plan.sensors),
                               device=plan.onboard_device, blueprint_device=drone.device)


def meter(plan: FlightPlan) -> Meter:
    """The meter that turns what the drone did into power (the energy model of the flight)."""
    return Meter(energy_model(plan), plan.drone, rho=plan.atmosphere.density)


def trajectory_accel(plan: FlightPlan, ctrl: CascadedController) -> float:
    """m/s^2: the pilots' trajectories' acceleration limit: a quarter of the thrust
    margin, at most ``MAX_ACCEL``, and no more than the velocity loop can follow
    (1.5 x its bandwidth)."""
    tw = plan.drone.thrust_to_weight_at(plan.atmosphere.density)
    return min(MAX_ACCEL, 0.25 * (tw - 1.0) * G, 1.5 * ctrl.k_vel)
