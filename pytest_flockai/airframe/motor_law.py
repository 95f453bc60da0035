"""Size laws of brushless multirotor motors, fitted over a published set of motors.

When a datasheet gives a motor's speed constant Kv but not its winding resistance Rm or
its no-load current I0 (DJI publishes neither), they come from the motor's mass with two
laws fitted, by least squares on logarithms, over one maker's line of multirotor outrunners
of 18 g to 360 g (``REFERENCE_MOTORS``):

- the motor constant Km = Kt / sqrt(Rm) (N m / sqrt(W), Kt = 1 / Kv in SI units), which
  does not depend on the winding: Km = KM_COEF m^KM_EXP. Geometric similarity gives
  m^(5/6) (Kt ~ N L^2, Rm ~ N^2 / L, so Km^2 ~ L^5); the set gives a steeper 0.92: the
  larger motors of a line are flatter and wider (a 6213 stator against a 1806), and a
  stator's torque grows with the square of its diameter at a given length.
- the no-load (iron and bearing) loss P0 = I0 x V at the test voltage, against mass and
  the no-load speed omega = Kv x V: P0 = IRON_COEF m^IRON_MASS_EXP omega^1.5, with the
  speed exponent of Steinmetz's law between hysteresis (~f) and eddy currents (~f^2);
  a free fit of the speed exponent gives 1.42 on this set.

Nothing here is fitted to a drone or to a flight time.
"""

from __future__ import annotations

import math

#: V, the voltage the no-load currents below are given at: the usual test voltage of
#: multirotor motor datasheets (T-Motor: "idle current (10V)"); estimate for this set
I0_TEST_V = 10.0

#: (model, Kv rpm/V, I0 A, Rm ohm, mass g): KDE Direct XF series specifications
#: (kdedirect.com product pages), as collected in the FAST-UAV motor catalogue of
#: Budinger, Reysset, Ochotorena and Delbecq, "Scaling laws and similarity models for the
#: preliminary design of multirotor drones", Aerospace Sci. Technol. 98 (2020) 105658
#: (github.com/SizingLab/FAST-UAV, data/catalogues/Motors/Motors_Data.csv).
REFERENCE_MOTORS = (
    ("KDE1806XF-2350", 2350, 0.4, 0.117, 18), ("KDE2304XF-2350", 2350, 0.7, 0.091, 24),
    ("KDE2306XF-2050", 2050, 0.6, 0.068, 29), ("KDE2306XF-2550", 2550, 1.2, 0.044, 29),
    ("KDE2315XF-2050", 2050, 1.3, 0.034, 64), ("KDE2315XF-965", 965, 0.5, 0.102, 64),
    ("KDE2315XF-885", 885, 0.5, 0.127, 64), ("KDE2814XF-775", 775, 0.5, 0.069, 95),
    ("KDE2814XF-515", 515, 0.3, 0.130, 95), ("KDE3510XF-715", 715, 0.5, 0.054, 120),
    ("KDE3510XF-475", 475, 0.2, 0.105, 120), ("KDE4012XF-400", 400, 0.5, 0.080, 145),
    ("KDE4014XF-380", 380, 0.5, 0.075, 160), ("KDE4213XF-360", 360, 0.4, 0.081, 175),
    ("KDE3520XF-400", 400, 0.3, 0.078, 190), ("KDE4215XF-465", 465, 0.7, 0.052, 195),
    ("KDE5215XF-435", 435, 1.4, 0.031, 305), ("KDE5215XF-330", 330, 0.7, 0.044, 305),
    ("KDE5215XF-220", 220, 0.5, 0.078, 305), ("KDE6213XF-185", 185, 0.6, 0.072, 360),
)

#: exponent of the no-load loss with speed (Steinmetz, see the module docstring)
IRON_SPEED_EXP = 1.5


def _kv_si(kv_rpm_v: float) -> float:
    return kv_rpm_v * 2.0 * math.pi / 60.0


def _line(xs, ys):
    """Least-squares (slope, intercept) of ys on xs."""
    n = len(xs)
    mx, my = sum(xs) / n, sum(ys) / n
    sxx = sum((x - mx) ** 2 for x in xs)
    slope = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx
    return slope, my - slope * mx


def _fit():
    log_m = [math.log(g / 1000.0) for *_, g in REFERENCE_MOTORS]
    log_km = [math.log((1.0 / _kv_si(kv)) / math.sqrt(rm)) for _, kv, _, rm, _ in REFERENCE_MOTORS]
    km_exp, km_b = _line(log_m, log_km)
    # P0 / omega^1.5 against mass
    log_p = [math.log(i0 * I0_TEST_V / (_kv_si(kv) * I0_TEST_V) ** IRON_SPEED_EXP)
             for _, kv, i0, _, _ in REFERENCE_MOTORS]
    fe_exp, fe_b = _line(log_m, log_p)
    return math.exp(km_b), km_exp, math.exp(fe_b), fe_exp


#: Km = KM_COEF x (motor mass in kg)^KM_EXP, N m / sqrt(W); and
#: P0 = IRON_COEF x (motor mass in kg)^IRON_MASS_EXP x omega^1.5, W: fitted over
#: REFERENCE_MOTORS at import (about 0.43 m^0.92 and 0.005 m^1.25 omega^1.5)
KM_COEF, KM_EXP, IRON_COEF, IRON_MASS_EXP = _fit()


def motor_constant(mass_kg: float) -> float:
    """Km = Kt / sqrt(Rm) of a motor of ``mass_kg`` (N m / sqrt(W))."""
    return KM_COEF * mass_kg ** KM_EXP


def winding_resistance(mass_kg: float, kv_si: float) -> float:
    """Rm (ohm) of a motor of ``mass_kg`` wound for ``kv_si`` (rad/s/V): Rm = (Kt / Km)^2."""
    return (1.0 / kv_si / motor_constant(mass_kg)) ** 2


def iron_loss_w(mass_kg: float, omega: float) -> float:
    """No-load loss (W) of a motor of ``mass_kg`` spinning at ``omega`` (rad/s)."""
    return IRON_COEF * mass_kg ** IRON_MASS_EXP * omega ** IRON_SPEED_EXP
