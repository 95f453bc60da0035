"""Energy components: each turns one tick's usage into electrical power.

The interface is small on purpose so users can write their own::

    class Heater(Component):
        def __init__(self, watts):
            super().__init__("heater", "de-icing heater")
            self.watts = watts
        def power(self, u):            # u: Usage of this tick
            return self.watts if u.airborne else 0.0

A component may split its power into named ``parts`` (the motors report
induced, profile and climb/drag power): it then implements ``power_parts(u)``
returning one number per part. ``bind(drone)`` is called once before each
flight to precompute from the airframe; keep ``power`` cheap, it runs on the
simulated clock.
"""

from __future__ import annotations

import math

from .. import _check
from ..errors import ConfigError
from ..physics import G, RHO_SEA_LEVEL



class Usage:
    """What the drone did during one energy tick; filled by the mission loop."""

    __slots__ = ("t", "dt", "airborne", "thrust", "v_rel_body", "soc_busy",
                 "tx_bytes", "tx_packets", "rx_bytes", "rx_packets", "io_busy")

    def __init__(self, rotor_count: int = 4):
        self.t = 0.0
        self.dt = 0.0
        self.airborne = False
        self.thrust = [0.0] * rotor_count      # N per rotor
        self.v_rel_body = (0.0, 0.0, 0.0)      # vehicle velocity relative to air, body frame
        self.soc_busy = 0.0                    # fraction of the tick the SoC was busy
        self.io_busy = 0.0
        self.tx_bytes = self.tx_packets = self.rx_bytes = self.rx_packets = 0


class Component:
    """Base class: a named source of power draw."""

    parts: tuple[str, ...] = ()

    def __init__(self, name: str, description: str = ""):
        if not isinstance(name, str) or not name or "." in name:
            raise ConfigError(f"component name = {name!r} is not allowed; expected a non-empty "
                              f"string without '.'")
        self.name = name
        self.description = description

    def bind(self, drone) -> None:
        """Precompute from the drone before a flight (optional)."""

    def bind_air_density(self, rho: float) -> None:
        """The flight's air density (kg/m^3), set before ``bind`` (optional)."""

    def power(self, u: Usage) -> float:  # pragma: no cover - interface
        raise NotImplementedError(f"{type(self).__name__}.power(usage) must return watts")

    def power_parts(self, u: Usage):
        return (self.power(u),)

    def set_description(self, text: str) -> "Component":
        self.description = str(text)
        return self

    def describe(self) -> dict:
        out = {"name": self.name, "type": type(self).__name__, "description": self.description}
        out.update(self.params())
        if self.parts:
            out["parts"] = list(self.parts)
        return out

    def params(self) -> dict:
        return {}

    def __repr__(self):
        p = ", ".join(f"{k}={v!r}" for k, v in self.params().items())
        return f"{type(self).__name__}({self.name!r}{', ' if p else ''}{p})"


class Constant(Component):
    """A constant draw for the whole mission (flight controller, a sensor, I/O)."""

    def __init__(self, name: str, power_w: float, description: str = ""):
        super().__init__(name, description)
        self.power_w = power_w

    @property
    def power_w(self) -> float:
        return self._w

    @power_w.setter
    def power_w(self, value):
        self._w = _check.non_negative("power_w", value, where=f"component {self.name!r}")

    def set_power(self, watts: float) -> "Constant":
        self.power_w = watts
        return self

    def power(self, u):
        return self._w

    def params(self):
        return {"power_w": self._w}


class SoC(Component):
    """On-board computer: idle power, active power while busy (ML tasks)."""

    parts = ("idle", "active")

    def __init__(self, name: str, idle_w: float, active_w: float, description: str = ""):
        super().__init__(name, description)
        where = f"component {name!r}"
        self.idle_w = _check.non_negative("idle_w", idle_w, where=where)
        self.active_w = _check.non_negative("active_w", active_w, where=where)

    def power_parts(self, u):
        b = u.soc_busy
        return (self.idle_w * (1.0 - b), self.active_w * b)

    def power(self, u):
        b = u.soc_busy
        return self.idle_w * (1.0 - b) + self.active_w * b

    def params(self):
        return {"idle_w": self.idle_w, "active_w": self.active_w}


class RadioLinear(Component):
    """802.11-style linear model (Feeney and Nilsson 2001): per packet
    E = m * bytes + b for sending and receiving, plus an idle draw."""

    parts = ("idle", "tx", "rx")

    def __init__(self, name: str, *, tx_uj_per_byte, tx_uj_per_packet, rx_uj_per_byte,
                 rx_uj_per_packet, idle_w, description: str = ""):
        super().__init__(name, description)
        w = f"component {name!r}"
        self.tx_uj_per_byte = _check.non_negative("tx_uj_per_byte", tx_uj_per_byte, where=w)
        self.tx_uj_per_packet = _check.non_negative("tx_uj_per_packet", tx_uj_per_packet, where=w)
        self.rx_uj_per_byte = _check.non_negative("rx_uj_per_byte", rx_uj_per_byte, where=w)
        self.rx_uj_per_packet = _check.non_negative("rx_uj_per_packet", rx_uj_per_packet, where=w)
        self.idle_w = _check.non_negative("idle_w", idle_w, where=w)

    def power_parts(self, u):
        dt = u.dt
        if dt <= 0.0:
            return (self.idle_w, 0.0, 0.0)
        tx = (self.tx_uj_per_byte * u.tx_bytes + self.tx_uj_per_packet * u.tx_packets) * 1e-6 / dt
        rx = (self.rx_uj_per_byte * u.rx_bytes + self.rx_uj_per_packet * u.rx_packets) * 1e-6 / dt
        return (self.idle_w, tx, rx)

    def power(self, u):
        return sum(self.power_parts(u))

    def params(self):
        return {k: getattr(self, k) for k in ("tx_uj_per_byte", "tx_uj_per_packet",
                                               "rx_uj_per_byte", "rx_uj_per_packet", "idle_w")}


class RadioStates(Component):
    """Radio as power states (paper Eq. for E_comm): P_tx t_tx + P_rx t_rx + P_idle t_idle,
    times from bytes over the bit rate. The paper's Wi-Fi: 8.4 W tx/rx, 4.2 W idle."""

    parts = ("idle", "tx", "rx")

    def __init__(self, name: str, *, tx_w=8.4, rx_w=8.4, idle_w=4.2, bitrate_bps=6e6,
                 description: str = ""):
        super().__init__(name, description)
        w = f"component {name!r}"
        self.tx_w = _check.non_negative("tx_w", tx_w, where=w)
        self.rx_w = _check.non_negative("rx_w", rx_w, where=w)
        self.idle_w = _check.non_negative("idle_w", idle_w, where=w)
        self.bitrate_bps = _check.positive("bitrate_bps", bitrate_bps, where=w)

    def power_parts(self, u):
        dt = u.dt
        if dt <= 0.0:
            return (self.idle_w, 0.0, 0.0)
        # every byte's airtime is charged in full (a short tick must not lose it);
        # only the idle time is what is left of the tick
        t_tx = u.tx_bytes * 8.0 / self.bitrate_bps
        t_rx = u.rx_bytes * 8.0 / self.bitrate_bps
        idle = max(0.0, dt - t_tx - t_rx)
        return (self.idle_w * idle / dt, self.tx_w * t_tx / dt, self.rx_w * t_rx / dt)

    def power(self, u):
        return sum(self.power_parts(u))

    def params(self):
        return {"tx_w": self.tx_w, "rx_w": self.rx_w, "idle_w": self.idle_w,
                "bitrate_bps": self.bitrate_bps}


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
      ``wake_interference`` of the fore rotors' wake they ingest, growing with
      the square of the wake skew sin(chi) = V_par / sqrt(V_par^2 + (V_ax + v_i)^2);
    - climb and drag power T V_ax (the tilted disc's propulsive power equals body
      drag times airspeed, so parasitic power comes out of the simulated tilt);
    - profile power c0 T^1.5 (1 + 4.65 mu^2), mu = V_par / (Omega R) (Leishman
      eq. 5.40), with c0 set by the hover figure of merit:
      FM = P_ideal / (kappa P_ideal + P0) -> c0 = (1/FM - kappa) / sqrt(2 rho A);
    - electrical power: mechanical power / (motor efficiency x ESC efficiency).
    """

    parts = ("induced", "profile", "climb_and_drag")

    def __init__(self, name: str = "motors", *, figure_of_merit, induced_power_factor=1.15,
                 motor_efficiency, esc_efficiency, wake_interference=0.0, rho=None,
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
        self._vi = []

    def bind_air_density(self, rho):
        self._rho_air = rho

    def bind(self, drone):
        A = drone.rotor.disc_area_m2
        rho = self.rho if self.rho is not None else self._rho_air
        self._inv2rhoA = 1.0 / (2.0 * rho * A)
        self._c0 = (1.0 / self.figure_of_merit - self.induced_power_factor) / math.sqrt(2.0 * rho * A)
        self._R = 0.5 * drone.rotor.diameter_m
        self._inv_kf = RHO_SEA_LEVEL / (drone.rotor.thrust_coeff * rho)   # kf is given at sea level
        self._inv_eta = 1.0 / (self.motor_efficiency * self.esc_efficiency)
        lay = drone.rotor_layout()
        self._dirs = [(x / math.hypot(x, y), y / math.hypot(x, y)) for x, y, _ in lay]
        self._n = len(lay)
        self._vi = [math.sqrt(drone.hover_thrust_per_rotor_n * self._inv2rhoA)] * self._n

    def power_parts(self, u):
        vx, vy, vax = u.v_rel_body
        vpar2 = vx * vx + vy * vy
        sqrt = math.sqrt
        vpar = sqrt(vpar2)
        kappa = self.induced_power_factor
        inv2rhoA, c0, R, inv_kf = self._inv2rhoA, self._c0, self._R, self._inv_kf
        vi_state = self._vi
        induced = profile = axial = 0.0
        wake_vi = 0.0
        thrust = u.thrust
        for i in range(self._n):
            T = thrust[i]
            if T <= 1e-9:
                continue
            vh2 = T * inv2rhoA
            v = vi_state[i]
            if v <= 0.0:
                v = sqrt(vh2)
            # Newton on f(v) = v sqrt(V_par^2 + (V_ax+v)^2) - vh^2, warm-started: two steps
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
            mu = vpar / (sqrt(T * inv_kf) * R)
            profile += c0 * T * sqrt(T) * (1.0 + 4.65 * mu * mu)
            wake_vi += v
        if self.wake_interference > 0.0 and vpar > 0.1 and wake_vi > 0.0:
            # aft rotors ingest the fore rotors' wake, skewed back by V_par
            n = self._n
            hx, hy = vx / vpar, vy / vpar
            vi_mean = wake_vi / n
            skew = vpar / sqrt(vpar2 + (vax + vi_mean) ** 2)
            skew *= skew    # the skewed wake reaches the aft rotors only as it flattens
            ws = [max(0.0, -(dx * hx + dy * hy)) for dx, dy in self._dirs]
            tot = sum(ws)
            if tot > 0.0:
                scale = self.wake_interference * vi_mean * skew * (0.5 * n) / tot
                induced += sum([w * thrust[i] for i, w in enumerate(ws)]) * scale
        inv_eta = self._inv_eta
        mech_axial = axial
        total = induced + profile + mech_axial
        if total < 0.0:  # autorotation-like descent: the rotors cannot give energy back
            mech_axial = -(induced + profile)
        return (induced * inv_eta, profile * inv_eta, mech_axial * inv_eta)

    def power(self, u):
        return sum(self.power_parts(u))

    def params(self):
        return {k: getattr(self, k) for k in ("figure_of_merit", "induced_power_factor",
                                               "motor_efficiency", "esc_efficiency",
                                               "wake_interference", "rho")}
