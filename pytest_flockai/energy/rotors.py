"""Rotor power: the motors' electrical power from momentum theory, every energy tick.

``Motors`` is the rotor component of every blueprint's energy model; ``HoverPower`` is the
FlockAI paper's constant hover power, kept for comparison. See ``components.py`` for the
component interface.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .. import _check
from ..errors import ConfigError
from ..physics import RHO_SEA_LEVEL, G
from .components import Component


class HoverPower(Component):
    """FlockAI-style motors: a constant hover power while airborne.

    P_hover = (m g)^1.5 / sqrt(2 rho A_total) / eta (paper Eq. for P_hover),
    with eta the efficiency chain; or a given ``power_w`` (the paper's released
    code used 95.02 W for the Mavic). Kept for comparison with ``Motors``.
    """

    def __init__(self, name: str = "motors", *, power_w: float | None = None,
                 efficiency: float | None = None, description: str = "constant hover power"):
        super().__init__(name, description)
        self.power_w = None if power_w is None else _check.non_negative("power_w", power_w,
                                                                       where=f"component {name!r}")
        self.efficiency = None if efficiency is None else _check.fraction(
            "efficiency", efficiency, where=f"component {name!r}", allow_zero=False)
        self._p = 0.0
        self._rho_air = RHO_SEA_LEVEL

    def bind_air_density(self, rho):
        self._rho_air = rho

    def bind(self, drone):
        if self.power_w is not None:
            self._p = self.power_w
            return
        m = drone.energy.component("motors") if self.efficiency is None else None
        eta = self.efficiency
        if eta is None:
            eta = (m.figure_of_merit * m.motor_efficiency * m.esc_efficiency
                   if isinstance(m, Motors) else 0.4)
        area = drone.airframe.rotor_count * drone.rotor.disc_area_m2
        self._p = (drone.mass_kg * G) ** 1.5 / math.sqrt(2.0 * self._rho_air * area) / eta

    @property
    def airborne_power_w(self) -> float:
        """The bound hover power (W), drawn while airborne."""
        return self._p

    def power(self, u):
        return self._p if u.airborne else 0.0

    def params(self):
        return {"power_w": self.power_w, "efficiency": self.efficiency}


#: Leishman, Principles of Helicopter Aerodynamics, 2nd ed. (2006), sec. 2.14: an empirical
#: fit of measured induced velocity in axial descent through the vortex-ring and turbulent-
#: wake states, v_i / v_h = kappa + k1 x + k2 x^2 + k3 x^3 + k4 x^4, x = V_c / v_h in [-2, 0].
#: kappa is taken as 1 here (the curve then meets momentum theory at hover and at x = -2,
#: the windmill-brake boundary); the induced power factor is applied separately.
VRS_K = (-1.125, -1.372, -1.718, -0.655)


def _descent_inflow(v_glauert: float, vax: float, vpar2: float, vh: float) -> float:
    """Induced velocity in descent: the empirical vortex-ring curve in axial descent,
    weighted by the axial share of the flow through the disc, V_ax^2 / (V_ax^2 + V_par^2)
    (forward speed blows the ring away, Glauert's relation holds again); never below
    Glauert's value. Our blend, not Leishman's: his curve is for axial flight only."""
    if vh <= 0.0:
        return v_glauert
    x = vax / vh
    if x < -2.0:
        return v_glauert
    k1, k2, k3, k4 = VRS_K
    v_emp = vh * (1.0 + x * (k1 + x * (k2 + x * (k3 + x * k4))))
    w = vax * vax / (vax * vax + vpar2)
    v = w * v_emp + (1.0 - w) * v_glauert
    return v if v > v_glauert else v_glauert


def wake_immersion(distance_m, sink_m_s, vpar_m_s, diameter_m, maximum=max, minimum=min):
    """Share of the fore rotor's wake an aft rotor ``distance_m`` behind it ingests.

    The wake leaves the fore disc skewed back by the in-plane airspeed V_par and sinks at
    V_ax + v_i (``sink_m_s``) relative to the rotor plane: by the aft rotor its centre lies
    h = L (V_ax + v_i) / V_par below the aft disc (the wake skew angle chi, tan chi =
    V_par / (V_ax + v_i), Leishman 2006 sec. 5.4), and the aft disc sits in it in proportion
    to 1 - h / D: fully when the wake is flat (fast flight), not at all once it passes a
    diameter below (slow flight, where the wake falls clear). Geometry, no fitted constant.
    Pure arithmetic: ``maximum``/``minimum`` = numpy's (or jax's) take arrays."""
    depth = distance_m * maximum(sink_m_s, 0.0) / maximum(vpar_m_s, 1e-9)
    return maximum(0.0, minimum(1.0, 1.0 - depth / diameter_m))


#: the DC motor model's fields of ``Motors`` (and of a blueprint's ``[energy]`` table)
MOTOR_FIELDS = ("motor_kv_rpm_v", "motor_rm_ohm", "motor_i0_a", "motor_i0_rad_s")


class MotorParams(NamedTuple):
    """A bound ``Motors``' coefficients as numbers (``Motors.batch_params``); ``dirs`` and
    ``vi0`` per rotor; ``model``: the DC motor model (else ``inv_eta``, a constant)."""

    inv2rhoA: float
    c0: float
    R: float
    inv_kf: float
    inv_eta: float
    hk: float
    kappa: float
    wake: float
    dirs: np.ndarray
    vi0: np.ndarray
    model: bool
    esc: float
    kv: float
    rm: float
    i0: float
    inv_w0: float
    D: float = 1.0         # rotor diameter, and an aft rotor's distance behind per unit
    L2: float = 0.0        # weight (``wake_immersion``); the defaults: no motors


class Motors(Component):
    """Rotor power from momentum theory, per rotor, every energy tick.

    For rotor i with thrust T (from the simulated rotor state), disc area A and
    the vehicle's velocity relative to the air split into the component along
    the rotor axis V_ax (climb, and the forward-tilted disc's share of forward
    speed) and in the disc plane V_par:

    - induced velocity v_i from Glauert's relation
      v_i = T / (2 rho A sqrt(V_par^2 + (V_ax + v_i)^2)) (Leishman 2006, eq. 5.22),
      so translational lift lowers it in forward flight; in descent through the
      vortex-ring state, where momentum theory does not hold, the empirical
      curve of ``_descent_inflow``;
    - induced power kappa T v_i, plus, for aft rotors, the share
      ``wake_interference`` of the fore rotors' wake they ingest, in proportion to how
      deep the aft disc sits in that wake (``wake_immersion``: the wake sinks at
      V_ax + v_i while it travels the rotor spacing at V_par; none at low speed, where
      it falls clear below the aft rotors, all of it once the wake is flat);
    - climb and drag power T V_ax (the tilted disc's propulsive power equals body
      drag times airspeed, so parasitic power comes out of the simulated tilt);
    - profile power c0 T^1.5 (1 + 4.65 mu^2), mu = V_par / (Omega R) (Leishman
      eq. 5.40), with c0 set by the hover figure of merit:
      FM = P_ideal / (kappa P_ideal + P0) -> c0 = (1/FM - kappa) / sqrt(2 rho A); less the
      work against the rotor's H-force, H V_par = (sigma Cd0 / 4) rho A (Omega R)^3 mu^2
      (sigma Cd0: the rotor's ``blade_drag``), which the physics applies
      (airframe/rotor_drag.py) and which therefore already shows in T V_ax through the
      tilt that overcomes it (blade-element theory: the profile power's 1 + 3 mu^2 is the
      torque's 1 + mu^2 plus the H-force's 2 mu^2; with a consistent sigma Cd0, as the
      datasheet blueprints have, the factor becomes 1 + 2.65 mu^2);
    - electrical power: mechanical power / (motor efficiency x ESC efficiency), with a
      constant ``motor_efficiency``; or, when the motor is given (``motor_kv_rpm_v``,
      ``motor_rm_ohm``, ``motor_i0_a`` at ``motor_i0_rad_s``), per rotor at its operating
      point: omega from the thrust (T = kf omega^2), torque Q = P_shaft / omega, current
      I = Q Kv + I0(omega), P_el = Q omega + I0(omega) omega / Kv + I^2 Rm (the DC motor
      model: back EMF omega / Kv, winding loss I^2 Rm), with the no-load current growing as
      I0(omega) = I0 sqrt(omega / omega_0) (iron loss ~ omega^1.5 over back EMF ~ omega,
      airframe/motor_law.py). The motor losses are shared out over the three parts in
      proportion; ``motor_efficiency`` is then only the hover figure for ``HoverPower``.
    """

    parts = ("induced", "profile", "climb_and_drag")
    # the DC motor model (set by _set_motor): all four given, or all None
    motor_kv_rpm_v: float | None
    motor_rm_ohm: float | None
    motor_i0_a: float | None
    motor_i0_rad_s: float | None

    def __init__(self, name: str = "motors", *, figure_of_merit, induced_power_factor=1.15,
                 motor_efficiency, esc_efficiency, wake_interference=0.0, rho=None,
                 motor_kv_rpm_v=None, motor_rm_ohm=None, motor_i0_a=None, motor_i0_rad_s=None,
                 description: str = "rotors: momentum theory per rotor"):
        super().__init__(name, description)
        w = f"component {name!r}"
        self.figure_of_merit = _check.fraction("figure_of_merit", figure_of_merit, where=w, allow_zero=False)
        self.induced_power_factor = _check.number("induced_power_factor", induced_power_factor,
                                                  where=w, minimum=1.0)
        self.motor_efficiency = _check.fraction("motor_efficiency", motor_efficiency, where=w,
                                                allow_zero=False)
        self.esc_efficiency = _check.fraction("esc_efficiency", esc_efficiency, where=w, allow_zero=False)
        self.wake_interference = _check.number("wake_interference", wake_interference, where=w,
                                               minimum=0.0, maximum=1.0)
        # None: the flight's air (Mission(atmosphere=...), sea level by default)
        self.rho = None if rho is None else _check.positive("rho", rho, where=w)
        self._rho_air = RHO_SEA_LEVEL
        if self.figure_of_merit * self.induced_power_factor >= 1.0:
            raise ConfigError(f"{w}: figure_of_merit x induced_power_factor = "
                              f"{self.figure_of_merit * self.induced_power_factor:.3f} must be < 1 "
                              f"(the rest is profile power)")
        self._vi: list[float] = []
        self._set_motor(w, motor_kv_rpm_v=motor_kv_rpm_v, motor_rm_ohm=motor_rm_ohm,
                        motor_i0_a=motor_i0_a, motor_i0_rad_s=motor_i0_rad_s)

    def _set_motor(self, w, **motor):
        given = [k for k, v in motor.items() if v is not None]
        if given and len(given) < len(motor):
            missing = sorted(set(motor) - set(given))
            raise ConfigError(f"{w}: {', '.join(given)} given without {', '.join(missing)}; "
                              f"allowed: all four motor fields (Kv, Rm, I0 and the speed I0 is "
                              f"given at) or none (a constant motor_efficiency)")
        for k, v in motor.items():
            setattr(self, k, None if v is None else _check.positive(k, v, where=w))

    def bind_air_density(self, rho):
        self._rho_air = rho

    def bind(self, drone):
        A = drone.rotor.disc_area_m2
        rho = self.rho if self.rho is not None else self._rho_air
        self._inv2rhoA = 1.0 / (2.0 * rho * A)
        self._c0 = (1.0 / self.figure_of_merit - self.induced_power_factor) / math.sqrt(2.0 * rho * A)
        self._R = 0.5 * drone.rotor.diameter_m
        self._D = drone.rotor.diameter_m
        self._L2 = 2.0 * drone.airframe.arm_length_m   # an aft rotor's distance behind: L2 x weight
        self._hk = 0.25 * drone.rotor.blade_drag * rho * A      # H V_par / ((Omega R)^3 mu^2)
        self._inv_kf = RHO_SEA_LEVEL / (drone.rotor.thrust_coeff * rho)   # kf is given at sea level
        self._inv_eta = 1.0 / (self.motor_efficiency * self.esc_efficiency)
        lay = drone.rotor_layout()
        self._dirs = [(x / math.hypot(x, y), y / math.hypot(x, y)) for x, y, _ in lay]
        self._n = len(lay)
        self._vi = [math.sqrt(drone.hover_thrust_per_rotor_n * self._inv2rhoA)] * self._n
        self._shaft = [0.0] * self._n          # per rotor, for the motor model
        self._omega = [0.0] * self._n
        self._kv = None if self.motor_kv_rpm_v is None else self.motor_kv_rpm_v * math.pi / 30.0

    def _electrical(self) -> float:
        """Electrical power (W) of the motors, each at its operating point (motor model)."""
        kv, rm, i0, w0 = self._kv, self.motor_rm_ohm, self.motor_i0_a, self.motor_i0_rad_s
        assert kv is not None and rm is not None and i0 is not None and w0 is not None, \
            "called only with the motor model (all four motor fields given)"
        inv_w0 = 1.0 / w0
        total = 0.0
        for p, om in zip(self._shaft, self._omega):
            if om <= 0.0:
                continue
            q = p / om if p > 0.0 else 0.0       # a motor does not give energy back
            i_nl = i0 * math.sqrt(om * inv_w0)
            cur = q * kv + i_nl
            total += q * om + i_nl * om / kv + cur * cur * rm
        return total

    def power_parts(self, u):
        vx, vy, vax = u.v_rel_body
        vpar2 = vx * vx + vy * vy
        sqrt = math.sqrt
        vpar = sqrt(vpar2)
        kappa = self.induced_power_factor
        inv2rhoA, c0, R, inv_kf, hk = self._inv2rhoA, self._c0, self._R, self._inv_kf, self._hk
        vi_state = self._vi
        induced = profile = axial = 0.0
        wake_vi = 0.0
        thrust = u.thrust
        shaft, omega, motor = self._shaft, self._omega, self._kv is not None
        for i in range(self._n):
            T = thrust[i]
            if T <= 1e-9:
                if motor:
                    shaft[i] = omega[i] = 0.0
                continue
            vh2 = T * inv2rhoA
            v = vi_state[i]
            if v <= 0.0:
                v = sqrt(vh2)
            # Newton on f(v) = v sqrt(V_par^2 + (V_ax+v)^2) - vh^2, warm-started: two steps,
            # unrolled (the hot loop of every flight: a fleet's profile spends a large share here)
            s = vax + v
            root = sqrt(vpar2 + s * s)
            v -= (v * root - vh2) / (root + v * s / root if root > 1e-9 else 1.0)
            if v < 0.0:
                v = 0.0
            s = vax + v
            root = sqrt(vpar2 + s * s)
            v -= (v * root - vh2) / (root + v * s / root if root > 1e-9 else 1.0)
            if v < 0.0:
                v = 0.0
            vi_state[i] = v
            if vax < 0.0:
                v = _descent_inflow(v, vax, vpar2, sqrt(vh2))
            induced += kappa * T * v
            axial += T * vax
            omega_r = sqrt(T * inv_kf) * R
            mu = vpar / omega_r
            p0h = c0 * T * sqrt(T)
            p0 = p0h * (1.0 + 4.65 * mu * mu) - hk * omega_r * omega_r * omega_r * mu * mu
            if p0 < p0h:
                p0 = p0h
            profile += p0
            wake_vi += v
            if motor:
                shaft[i] = kappa * T * v + T * vax + p0
                omega[i] = omega_r / R
        if self.wake_interference > 0.0 and vpar > 0.1 and wake_vi > 0.0:
            # aft rotors ingest the fore rotors' wake, skewed back by V_par and sinking below
            # them as it goes: immersed by wake_immersion() of their distance behind
            n = self._n
            hx, hy = vx / vpar, vy / vpar
            vi_mean = wake_vi / n
            ws = [max(0.0, -(dx * hx + dy * hy)) for dx, dy in self._dirs]
            tot = sum(ws)
            if tot > 0.0:
                scale = self.wake_interference * vi_mean * (0.5 * n) / tot
                sink, span = vax + vi_mean, self._D
                for i, w in enumerate(ws):
                    if w > 0.0:
                        extra = w * thrust[i] * scale * wake_immersion(
                            self._L2 * w, sink, vpar, span)
                        induced += extra
                        if motor:
                            shaft[i] += extra
        inv_eta = self._inv_eta
        mech_axial = axial
        total = induced + profile + mech_axial
        if total < 0.0:  # autorotation-like descent: the rotors cannot give energy back
            mech_axial = -(induced + profile)
        elif motor and total > 1e-12:
            inv_eta = self._electrical() / (total * self.esc_efficiency)
        return (induced * inv_eta, profile * inv_eta, mech_axial * inv_eta)

    def power(self, u):
        return sum(self.power_parts(u))

    def batch_params(self) -> MotorParams:
        """The bound coefficients, for the batched backend (after ``bind``)."""
        return MotorParams(
            inv2rhoA=self._inv2rhoA, c0=self._c0, R=self._R, inv_kf=self._inv_kf,
            inv_eta=self._inv_eta, hk=self._hk, kappa=self.induced_power_factor,
            wake=self.wake_interference, dirs=np.asarray(self._dirs, dtype=float),
            vi0=np.asarray(self._vi, dtype=float), model=self._kv is not None,
            esc=self.esc_efficiency, kv=self._kv or 1.0, rm=self.motor_rm_ohm or 0.0,
            i0=self.motor_i0_a or 0.0,
            inv_w0=1.0 / self.motor_i0_rad_s if self.motor_i0_rad_s else 0.0,
            D=self._D, L2=self._L2)

    def params(self):
        out = {k: getattr(self, k) for k in ("figure_of_merit", "induced_power_factor",
                                              "motor_efficiency", "esc_efficiency",
                                              "wake_interference", "rho")}
        if self.motor_kv_rpm_v is not None:
            out.update({k: getattr(self, k) for k in MOTOR_FIELDS})
        return out
