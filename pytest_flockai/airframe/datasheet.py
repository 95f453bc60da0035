"""Datasheet-level blueprints: every parameter a datasheet does not give, derived.

A blueprint with a ``[datasheet]`` table gives what a maker publishes: mass,
diagonal, rotor count, body size, top speed, propeller diameter and pitch, and,
where known, the motor's Kv, winding resistance and no-load current (the
battery stays in ``[battery]``: cells, capacity, chemistry). ``expand()`` turns
it into the ``[airframe]``, ``[rotor]`` and ``[energy]`` tables the simulator
flies, with one set of global constants (below, each with its source) and no
value fitted to any drone. A field written in those tables wins over the
derived one ("fields a user knows better").

- Propeller: blade-element momentum theory of a hovering rotor with ideal
  twist (Leishman, Principles of Helicopter Aerodynamics, 2nd ed. 2006, eq.
  3.61): C_T = (sigma a / 2)(theta_75 / 3 - lambda / 2), lambda = sqrt(C_T / 2),
  theta_75 = atan(pitch / (0.75 pi D)) + the section's zero-lift angle.
  Profile power sigma C_d / 8 with a section drag that falls with the blade's
  Reynolds number at 0.75 R in hover, C_d ~ Re^-1/2 (laminar skin friction,
  Blasius; the regime of small propellers, Lissaman, Annu. Rev. Fluid Mech. 15,
  1983) up to Re 1e5, C_d ~ Re^-1/5 above (turbulent skin friction: the rotors of
  large drones; ``section_drag``). The figure of merit follows: FM = C_T^1.5 /
  sqrt(2) / C_P.
- Motor: the DC motor model (Kv, winding resistance Rm, no-load current I0),
  eta = Q omega / (V I) with I = Kt Q + I0, V = omega / Kv + I Rm, at hover (the energy
  model recomputes it at every operating point, energy/rotors.py Motors). Without Rm or
  I0: the size laws of ``motor_law.py``, fitted over a published line of 20 multirotor
  motors of 18-360 g (Km = Kt / sqrt(Rm) ~ m^0.92, no-load loss ~ m^1.25 omega^1.5), for
  motors weighing MOTOR_MASS_SHARE of the take-off mass they are sized for.
- Body: drag areas from the top speed, inertia from a box and rotor masses.
- Avionics (flight controller, video link, camera, small sensors) by drone class
  (``avionics``), unless the blueprint's ``[energy]`` gives a flight controller power.
"""

from __future__ import annotations

import math

from ..energy.rotors import MOTOR_FIELDS
from ..errors import ConfigError
from ..physics import RHO_SEA_LEVEL, G
from . import motor_law as _law
from . import rotor_drag as _rotor_drag
from .params import Field, Section

INCH = 0.0254                      # m (exact, by definition)
#: m^2/s, kinematic viscosity of the ICAO standard atmosphere at sea level
#: (mu = 1.7894e-5 Pa s over rho = 1.225 kg/m^3)
NU_SEA_LEVEL = 1.46e-5
#: 1/rad, section lift-curve slope, Leishman (2006) ch. 3 worked examples (2 pi less ~10 %)
LIFT_SLOPE = 5.73
#: blade chord over tip radius at 0.75 R: Brandt and Selig (AIAA 2011-1255) measured
#: 0.1-0.2 for 9-11 in propellers; 0.15 taken
CHORD_RATIO = 0.15
#: deg, pitch added to the geometric pitch for a cambered section's zero-lift angle
#: (Clark-Y-like sections: -3 to -4 deg, Abbott and von Doenhoff, Theory of Wing Sections,
#: 1959); 3.7 makes this model give the UIUC static C_T = 0.11 of the APC 9x4.7 (below)
ZERO_LIFT_DEG = 3.7
#: induced power factor kappa, Leishman (2006): ~1.15
KAPPA = 1.15
#: section drag anchor: UIUC Propeller Data Site, APC 9x4.7 static test, C_T = 0.11,
#: C_P = 0.045 at ~5000 rpm (Re at 0.75 R about 6e4): C_P / 24.35 - kappa C_T'^1.5 / sqrt 2
#: (helicopter normalisation, C_T' = C_T / 7.75) leaves profile power sigma C_d / 8 with
#: sigma = 2 x 0.15 / pi: C_d = 0.040
CD_REF, RE_REF = 0.040, 6.0e4
#: C_d ~ Re^CD_RE_EXP, laminar skin friction (Blasius: C_f = 1.328 Re^-1/2)
CD_RE_EXP = -0.5
#: above this blade Reynolds number the boundary layer is turbulent before it can separate
#: laminar: the critical Reynolds number of thin cambered sections, 7e4-1e5 (McMasters and
#: Henderson, "Low-speed single-element airfoil synthesis", Tech. Soaring 6, 1980; Lissaman
#: 1983, fig. 1), and the drag follows turbulent skin friction, C_f = 0.074 Re^-1/5
#: (Schlichting, Boundary-Layer Theory, ch. 21): 1e5 and -0.2 taken
RE_TURBULENT, CD_RE_EXP_TURBULENT = 1.0e5, -0.2
#: estimate: the motors of a multirotor weigh about 10 % of the take-off mass they are sized
#: for (all motors; the maximum take-off mass where the maker publishes one)
MOTOR_MASS_SHARE = 0.10
#: estimate: design thrust-to-weight at full throttle when no Kv is given (the Mavic's
#: 5 m/s ascent and 72 km/h at 35 deg tilt need 1.22; 2-3 is the usual design range)
THRUST_TO_WEIGHT = 2.5
ESC_EFFICIENCY = 0.95              # estimate: typical ESC efficiency at cruise load
#: brushed coreless motors with their MOSFET drive (``motor_type = "brushed-coreless"``), at
#: hover: the Crazyflie 2.0's 7x16 mm motors, the one small coreless propulsion with published
#: measurements. Electrical power of motors and drive 6.50 W for 27 g of thrust (Bitcraze
#: thrust-stand table, wiki.bitcraze.io misc:investigations:thrust: 2.00 A at 3.69 V
#: interpolated at 27 g, less the 0.24 A drawn at zero PWM); shaft power 3.06 W (Foerster,
#: "System identification of the Crazyflie 2.0 nano quadrocopter", ETH Zurich 2015: torque
#: 0.005964552 T + 1.563383e-5 N m at 1862 rad/s, from his thrust and speed maps at 6.6 g per
#: rotor): 3.06 / 6.50 = 0.47, motor and drive together (the ESC efficiency is then 1)
CORELESS_EFFICIENCY = 0.47
#: s, motor and propeller time constant: 30 ms at 0.221 m (bench tests of 8-10 in
#: propellers on 2204-2306 motors, 20-50 ms), scaled with diameter
TAU_REF_S, TAU_REF_D = 0.030, 0.221
#: deg, attitude limit at top speed (the drag rule): DJI S-mode tilt
TOP_TILT_DEG = 35.0
#: Cd x A seen from above per m^2 of diagonal^2: Mavic 2 Pro estimate (body and arms
#: ~0.035 m^2 from above, Cd ~0.9) = 0.030 m^2 over 0.354^2 m^2
TOP_CDA_PER_DIAG2 = 0.030 / 0.354 ** 2
#: share of the fore rotors' near-wake induced velocity the aft rotors ingest once the wake is
#: flat (energy/rotors.py Motors: weighted by the wake skew squared and by how far each rotor
#: is aft). Geometry, not a fit: in the "x" layout each aft rotor sits directly behind a fore
#: rotor, one to two diameters downstream, so a flattened wake covers its whole disc; the
#: near-wake velocity (v_i, not the far wake's 2 v_i: the wake has not contracted yet)
WAKE_INTERFERENCE = 1.0
BODY_MASS_SHARE = 0.6              # estimate: 60 % of the mass in the body box, 40 % at the rotors


class Datasheet(Section):
    """The ``[datasheet]`` table: what a maker publishes."""

    TABLE = "datasheet"
    FIELDS = {
        "mass_kg": Field("pos", doc="take-off mass", unit="kg", bounds=(0.005, 50.0, "5 g to 50 kg")),
        "max_takeoff_mass_kg": Field("optpos", None, unit="kg",
                                     bounds=(0.005, 100.0, "5 g to 100 kg"),
                                     doc="maximum take-off mass, payload included; the motors "
                                         "are sized for it (default: mass_kg)"),
        "diagonal_m": Field("pos", doc="rotor axis to rotor axis across the frame", unit="m",
                            bounds=(0.02, 4.0, "diagonal in metres, not millimetres")),
        "rotor_count": Field("rotors", 4),
        "body_size_m": Field("vec3pos", doc="body box L W H", unit="m",
                             bounds=(0.005, 5.0, "body box edges in metres, not millimetres")),
        "top_speed_m_s": Field("pos", doc="maximum level speed", unit="m/s",
                               bounds=(1.0, 60.0, "1 to 60 m/s (216 km/h)")),
        "prop_diameter_in": Field("pos", unit="in", bounds=(0.8, 63.0, "propellers from 20 mm to 63 in")),
        "prop_pitch_in": Field("pos", unit="in", bounds=(0.2, 40.0, "a twisted propeller's geometric pitch")),
        "prop_blades": Field("blades", 2),
        "motor_kv": Field("optpos", None, unit="rpm/V", bounds=(10.0, 100000.0, "rpm per volt"),
                          doc="speed constant; default: the design thrust-to-weight at the pack voltage"),
        "motor_rm_ohm": Field("optpos", None, unit="ohm", bounds=(0.001, 50.0, "winding resistance"),
                              doc="winding resistance; default: the size law of motor_law.py"),
        "motor_i0_a": Field("optpos", None, unit="A", bounds=(0.001, 20.0, "no-load current"),
                            doc="no-load current at motor_i0_v; default: the size law of motor_law.py"),
        "motor_type": Field("motor_type", "brushless",
                            doc="brushless (the DC motor model and size laws) or brushed-coreless "
                                "(toy drones: a constant CORELESS_EFFICIENCY from published "
                                "measurements)"),
        "motor_i0_v": Field("pos", _law.I0_TEST_V, unit="V",
                            bounds=(0.5, 100.0, "the test voltage of a no-load current"),
                            doc="the voltage motor_i0_a is given at (default 10 V, the usual test "
                                "voltage of motor datasheets)"),
    }


def section_drag(reynolds, maximum=max):
    """Profile drag coefficient of the blade section at ``reynolds`` (at 0.75 R): laminar
    skin friction below RE_TURBULENT, turbulent above (the larger of the two laws, which
    meet there). Pure arithmetic: ``maximum=numpy.maximum`` (or jax's) takes arrays."""
    laminar = CD_REF * (reynolds / RE_REF) ** CD_RE_EXP
    at_transition = CD_REF * (RE_TURBULENT / RE_REF) ** CD_RE_EXP
    turbulent = at_transition * (reynolds / RE_TURBULENT) ** CD_RE_EXP_TURBULENT
    return maximum(laminar, turbulent)


def propeller(diameter_m: float, pitch_m: float, blades: int, reynolds: float | None = None):
    """Static (C_T, C_P, FM) in propeller form (T = C_T rho n^2 D^4, P = C_P rho n^3 D^5) of
    a propeller at blade Reynolds number ``reynolds`` (at 0.75 R; None: the anchor's)."""
    sigma = blades * CHORD_RATIO / math.pi
    theta = math.atan(pitch_m / (0.75 * math.pi * diameter_m)) + math.radians(ZERO_LIFT_DEG)
    ct = 0.01
    for _ in range(60):            # fixed point of C_T = (sigma a / 2)(theta/3 - sqrt(C_T/2)/2)
        ct = max(1e-6, 0.5 * sigma * LIFT_SLOPE * (theta / 3.0 - 0.5 * math.sqrt(0.5 * ct)))
    cd = section_drag(reynolds or RE_REF)
    ideal = ct ** 1.5 / math.sqrt(2.0)
    cp = KAPPA * ideal + sigma * cd / 8.0
    # helicopter (rho A (Omega R)^k) to propeller (rho n^k D^(k+2)) normalisation
    return ct * math.pi ** 3 / 4.0, cp * math.pi ** 4 / 4.0, ideal / cp


def hover_propeller(diameter_m: float, pitch_m: float, blades: int, thrust_n: float):
    """(C_T, C_P, FM, omega) at the Reynolds number of hover with ``thrust_n`` per rotor."""
    re = RE_REF
    for _ in range(20):            # omega depends on C_T, Re on omega: converge
        ct, cp, fm = propeller(diameter_m, pitch_m, blades, re)
        n = math.sqrt(thrust_n / (ct * RHO_SEA_LEVEL * diameter_m ** 4))
        omega = 2.0 * math.pi * n
        re = 0.75 * omega * 0.5 * diameter_m * CHORD_RATIO * 0.5 * diameter_m / NU_SEA_LEVEL
    return ct, cp, fm, omega


def motor_efficiency(torque_nm: float, omega: float, *, kv_rad: float, rm: float, i0: float) -> float:
    """Efficiency of a DC motor (SI speed constant ``kv_rad`` in rad/s/V) giving torque at omega."""
    current = torque_nm * kv_rad + i0
    volts = omega / kv_rad + current * rm
    return torque_nm * omega / (volts * current)


def _motor(ds: Section, mass: float, n: int, q_hover: float, om_hover: float, om_max: float,
           pack_v: float):
    """(eta at hover, Kv in rad/s/V, Rm, I0) from the datasheet or the defaults."""
    # a motor sized for the maximum take-off mass: its full speed at that thrust
    scale = max(mass, ds.max_takeoff_mass_kg or mass) / mass
    om_max = om_max * math.sqrt(scale)
    kv = ds.motor_kv * 2.0 * math.pi / 60.0 if ds.motor_kv else om_max / (0.85 * pack_v)
    m_motor = MOTOR_MASS_SHARE * scale * mass / n
    rm = ds.motor_rm_ohm if ds.motor_rm_ohm is not None else _law.winding_resistance(m_motor, kv)
    if ds.motor_i0_a is not None:
        # measured at the no-load speed Kv x motor_i0_v; at hover by the iron-loss law
        # (loss ~ omega^1.5 over back EMF ~ omega)
        i0 = ds.motor_i0_a * (om_hover / (kv * ds.motor_i0_v)) ** (_law.IRON_SPEED_EXP - 1.0)
    else:                                         # the iron loss as current at the back EMF
        i0 = _law.iron_loss_w(m_motor, om_hover) * kv / om_hover
    return motor_efficiency(q_hover, om_hover, kv_rad=kv, rm=rm, i0=i0), kv, rm, i0


def _max_speed(ds, km_coef, kv, rm, i0, pack_v, om_hover):
    """Full-throttle rotor speed: from the motor equation at the pack voltage when Kv is
    given, else from the design thrust-to-weight."""
    if not ds.motor_kv:
        return om_hover * math.sqrt(THRUST_TO_WEIGHT)
    lo, hi = 0.0, pack_v * kv
    for _ in range(60):   # V = omega / Kv + (km omega^2 Kv + I0) Rm, bisection
        mid = 0.5 * (lo + hi)
        if mid / kv + (km_coef * mid * mid * kv + i0) * rm < pack_v:
            lo = mid
        else:
            hi = mid
    return lo


def _body(ds: Section, mass: float, n: int, h_top: float):
    """Inertia and drag areas. The drag areas close the force balance at top speed and
    TOP_TILT_DEG: m g tan(tilt) = 1/2 rho CdA V^2 + H, H the rotors' drag there (rotor_drag.py;
    in-plane speed V cos(tilt), its horizontal share cos(tilt)); the body's CdA is what is left
    once the rotors' share is taken out (else the H-force would be counted twice)."""
    L, W, H = ds.body_size_m
    arm = 0.5 * ds.diagonal_m
    mb, mr = BODY_MASS_SHARE * mass, (1.0 - BODY_MASS_SHARE) * mass / n
    lever = arm / math.sqrt(2.0)      # rotors evenly around: mean of r^2 sin^2 is r^2 / 2
    inertia = [mb / 12.0 * (W * W + H * H) + n * mr * lever ** 2,
               mb / 12.0 * (L * L + H * H) + n * mr * lever ** 2,
               mb / 12.0 * (L * L + W * W) + n * mr * arm ** 2]
    t = math.radians(TOP_TILT_DEG)
    body_force = max(mass * G * math.tan(t) - h_top * math.cos(t), 0.2 * mass * G * math.tan(t))
    seen = 2.0 * body_force / (RHO_SEA_LEVEL * ds.top_speed_m_s ** 2)
    az = TOP_CDA_PER_DIAG2 * ds.diagonal_m ** 2
    ax2 = (seen ** 2 - (az * math.sin(t)) ** 2)
    ax = math.sqrt(ax2) / math.cos(t) if ax2 > 0 else 0.2 * seen
    return {"mass_kg": mass, "arm_length_m": arm, "layout": "x", "rotor_count": n,
            "inertia_kg_m2": inertia, "body_size_m": list(ds.body_size_m),
            "drag_area_m2": [ax, 1.2 * ax if L > 1.3 * W else ax, az], "max_tilt_deg": TOP_TILT_DEG}


def derive(ds: Section, pack_v: float) -> dict:
    """The ``airframe``, ``rotor`` and ``energy`` tables derived from a datasheet, plus the
    ``derived`` figures (C_T, C_P, FM, Reynolds number, motor values) for inspection."""
    mass, n = ds.mass_kg, ds.rotor_count
    D, pitch = ds.prop_diameter_in * INCH, ds.prop_pitch_in * INCH
    thrust = mass * G / n
    ct, cp, fm, om_h = hover_propeller(D, pitch, ds.prop_blades, thrust)
    kf = ct * RHO_SEA_LEVEL * D ** 4 / (4.0 * math.pi ** 2)
    kq = cp * RHO_SEA_LEVEL * D ** 5 / (8.0 * math.pi ** 3)
    q_h = kq * om_h ** 2
    om_design = om_h * math.sqrt(THRUST_TO_WEIGHT)
    eta, kv, rm, i0 = _motor(ds, mass, n, q_h, om_h, om_design, pack_v)
    om_max = _max_speed(ds, kq, kv, rm, i0, pack_v, om_h)
    re_h = 0.75 * om_h * 0.5 * D * CHORD_RATIO * 0.5 * D / NU_SEA_LEVEL
    blade_drag = ds.prop_blades * CHORD_RATIO / math.pi * section_drag(re_h)
    rotor = {"diameter_m": D, "thrust_coeff": kf, "torque_coeff": kq, "max_speed_rad_s": om_max,
             "time_constant_s": TAU_REF_S * D / TAU_REF_D, "blade_drag": blade_drag}
    energy = {"figure_of_merit": fm, "induced_power_factor": KAPPA, "motor_efficiency": eta,
              "esc_efficiency": ESC_EFFICIENCY, "wake_interference": WAKE_INTERFERENCE,
              "motor_kv_rpm_v": kv * 30.0 / math.pi, "motor_rm_ohm": rm, "motor_i0_a": i0,
              "motor_i0_rad_s": om_h}
    if ds.motor_type == "brushed-coreless":       # no DC motor model: a measured constant
        for k in MOTOR_FIELDS:
            del energy[k]
        eta = energy["motor_efficiency"] = CORELESS_EFFICIENCY
        energy["esc_efficiency"] = 1.0
    derived = {"ct": ct, "cp": cp, "figure_of_merit": fm, "hover_rad_s": om_h,
               "reynolds_075": re_h, "blade_drag": blade_drag,
               "motor_efficiency": eta, "motor_kv_rpm_v": kv * 60.0 / (2.0 * math.pi),
               "motor_rm_ohm": rm, "motor_i0_a": i0}
    if ds.motor_type == "brushed-coreless":       # the brushless laws' values do not apply
        derived.update(motor_kv_rpm_v=None, motor_rm_ohm=None, motor_i0_a=None)
    h_top = n * _rotor_drag.h_force(blade_drag, D, kf, RHO_SEA_LEVEL, thrust / math.cos(
        math.radians(TOP_TILT_DEG)), ds.top_speed_m_s * math.cos(math.radians(TOP_TILT_DEG)))
    return {"airframe": _body(ds, mass, n, h_top), "rotor": rotor, "energy": energy, "derived": derived}


#: avionics by drone class, W: (largest take-off mass of the class in kg, flight controller
#: with its IMU, barometer, compass and GNSS receiver, video downlink, camera and gimbal)
#: - toy (Ryze Tello class, up to 100 g): flight controller MCU 0.3 W (STM32F4 class: under
#:   100 mA at 3.3 V, ST STM32F405 datasheet); 2.4 GHz 802.11n video link 0.8 W (the idle
#:   802.11 power of Feeney and Nilsson, IEEE INFOCOM 2001, as the radio model); a vision
#:   processor 1 W (Intel Movidius Myriad 2 product brief: 1 W) and a 720p camera 0.5 W
#:   (estimate) counted as the camera;
#: - sub-250 g (DJI Mini class): flight controller 1.0 W (estimate: an STM32-class MCU,
#:   IMU, barometer and GNSS receiver, 0.3 + 0.15 + 0.5 W), video link 0.8 W (as above),
#:   a 1/2.3-1/1.3 in camera with a 3-axis gimbal 1.5 W (estimate);
#: - larger drones: the figures the issue-15 blueprints used (flight controller 2.5 W, the
#:   generic autopilot of generic-hexa-680.toml; camera and gimbal at idle video 2.0 W;
#:   video link 0.8 W).
#: Estimates where not cited; they are 2-10 % of a small drone's power and under 2 % of a
#: drone over 1 kg.
AVIONICS_CLASSES = ((0.100, 0.3, 0.8, 1.5), (0.250, 1.0, 0.8, 1.5), (math.inf, 2.5, 0.8, 2.0))
#: W: storage and buses, and the four small sensors of every blueprint (u-blox M8 GNSS 0.15 W,
#: Bosch BMI088 IMU 0.02 W, magnetometer 0.01 W, BMP388 barometer 0.005 W: their datasheets)
IO_W = 0.3
SMALL_SENSORS_W = {"gps": 0.15, "imu": 0.02, "compass": 0.01, "barometer": 0.005}


def avionics(mass_kg: float) -> dict:
    """The ``[energy]`` avionics (flight controller, I/O, sensors, camera, video link) of a
    drone of ``mass_kg`` take-off mass, by class (AVIONICS_CLASSES)."""
    _, fc, link, camera = next(c for c in AVIONICS_CLASSES if mass_kg <= c[0])
    io = IO_W if mass_kg > AVIONICS_CLASSES[0][0] else 0.0
    return {"flight_controller_w": fc, "io_w": io,
            "sensors": {"camera": camera, "video_link": link, **SMALL_SENSORS_W}}


def expand(data: dict, where: str) -> tuple[dict, dict | None]:
    """A blueprint dict with its ``[datasheet]`` expanded into the simulator's tables (the
    blueprint's own values win); returns (blueprint dict, derived figures or None)."""
    if "datasheet" not in data:
        return data, None
    table = data["datasheet"]
    if not isinstance(table, dict):
        raise ConfigError(f"{where} [datasheet]: expected a table, got {table!r}")
    ds = Datasheet(table, where=f"{where} [datasheet]")
    pack_v = _pack_voltage(data.get("battery"), where)
    out = derive(ds, pack_v)
    merged = {k: v for k, v in data.items() if k != "datasheet"}
    if "flight_controller_w" not in data.get("energy", {}):
        out["energy"].update(avionics(ds.mass_kg))
    for sec in ("airframe", "rotor", "energy"):
        own = data.get(sec, {})
        if not isinstance(own, dict):
            raise ConfigError(f"{where} [{sec}]: expected a table, got {own!r}")
        merged[sec] = {**out[sec], **own}
    own_energy = data.get("energy", {})
    if "motor_efficiency" in own_energy and not any(k in own_energy for k in MOTOR_FIELDS):
        for k in MOTOR_FIELDS:         # the user's constant efficiency wins over the motor model
            del merged["energy"][k]
    return merged, out["derived"]


def _pack_voltage(battery, where: str) -> float:
    if not isinstance(battery, dict) or "voltage_v" not in battery:
        raise ConfigError(f"{where} [battery]: a datasheet blueprint needs voltage_v "
                          f"(the pack's nominal voltage) for the motor model")
    v = battery["voltage_v"]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not v > 0:
        raise ConfigError(f"{where} [battery]: voltage_v = {v!r} is out of range; allowed: > 0 V")
    return float(v)
