"""Validated parameter sections.

A ``Section`` holds the fields of one blueprint table (``[airframe]``,
``[battery]``...). Every assignment, from a TOML file or from user code
(``drone.battery.capacity_mah = 4500``), goes through the field's validator,
so a bad value is refused where it enters, with the field, the value and what
is allowed in the message.
"""

from __future__ import annotations

import copy
import math
from typing import TYPE_CHECKING, Any

from .. import _check
from ..energy import battery as _cells
from ..errors import ConfigError, close_matches
from .rotor_drag import BLADE_DRAG_DEFAULT


class Field:
    """One blueprint field: its kind (how it is checked), default, doc and unit, and
    optional physical-plausibility ``bounds`` (low, high, why), so a unit slip (a
    propeller of 22.1 m, a 0.3 s control rate) is refused with the reason."""

    __slots__ = ("kind", "default", "doc", "unit", "bounds")

    def __init__(self, kind: str, default=..., doc: str = "", unit: str = "", bounds=None):
        self.kind, self.default, self.doc, self.unit = kind, default, doc, unit
        self.bounds = bounds

    @property
    def required(self) -> bool:
        return self.default is ...

    def check(self, name: str, value, where: str):
        value = self._check_kind(name, value, where)
        if self.bounds is not None and value is not None:
            lo, hi, why = self.bounds
            items = value if isinstance(value, (list, tuple)) else (value,)
            if any(not lo <= v <= hi for v in items):
                unit = f" {self.unit}" if self.unit else ""
                raise ConfigError(f"{where}: {name} = {value!r} is not physically plausible; "
                                  f"allowed: {lo:g} to {hi:g}{unit} ({why})")
        return value

    def _check_kind(self, name: str, value, where: str):
        k = self.kind
        if k == "pos":
            return _check.positive(name, value, where=where)
        if k == "nonneg":
            return _check.non_negative(name, value, where=where)
        if k == "frac01":          # (0, 1]
            return _check.number(name, value, where=where, minimum=0.0, maximum=1.0,
                                 min_inclusive=False)
        if k == "reserve":         # [0, 1)
            return _check.number(name, value, where=where, minimum=0.0, maximum=1.0,
                                 max_inclusive=False)
        if k == "angle":
            return _check.number(name, value, where=where, minimum=0.0, maximum=89.0,
                                 min_inclusive=False)
        if k == "pitch":
            return _check.number(name, value, where=where, minimum=-90.0, maximum=90.0)
        if k == "fov":
            return _check.number(name, value, where=where, minimum=1.0, maximum=179.0)
        if k == "vec3pos":
            return _check.vector(name, value, 3, where=where, positive_entries=True)
        if k == "rotors":
            if isinstance(value, bool) or not isinstance(value, int) or value not in (4, 6, 8):
                raise ConfigError(f"{where}: {name} = {value!r} is not allowed; allowed: 4, 6, 8")
            return value
        if k == "blades":
            if isinstance(value, bool) or not isinstance(value, int) or not 2 <= value <= 6:
                raise ConfigError(f"{where}: {name} = {value!r} is not allowed; allowed: a whole "
                                  f"number of propeller blades from 2 to 6")
            return value
        if k == "pixels":
            if isinstance(value, bool) or not isinstance(value, int) or value <= 0 or value > 4096:
                raise ConfigError(f"{where}: {name} = {value!r} is not allowed; "
                                  f"allowed: a whole number of pixels from 1 to 4096")
            return value
        if k == "optpos":          # a positive number, or None: derived
            return None if value is None else _check.positive(name, value, where=where)
        if k == "cells":           # None: derived from the nominal voltage
            if value is None:
                return None
            if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= 14:
                raise ConfigError(f"{where}: {name} = {value!r} is not allowed; allowed: a whole "
                                  f"number of cells in series from 1 to 14 (1S to 14S packs)")
            return value
        if k == "chemistry":
            return _check.choice(name, value, _cells.CHEMISTRIES, where=where)
        if k == "layout":
            return _check.choice(name, value, ("x",), where=where)
        if k == "motor_type":
            return _check.choice(name, value, ("brushless", "brushed-coreless"), where=where)
        if k == "str":
            if not isinstance(value, str) or not value:
                raise ConfigError(f"{where}: {name} = {value!r} is not allowed; expected a non-empty string")
            return value
        if k == "strlist":
            if not isinstance(value, (list, tuple)) or not all(isinstance(v, str) for v in value):
                raise ConfigError(f"{where}: {name} = {value!r} is not allowed; expected a list of strings")
            return list(value)
        if k == "powers":          # table of name -> watts
            if not isinstance(value, dict):
                raise ConfigError(f"{where}: {name} = {value!r} is not allowed; expected a table of name = watts")
            return {str(kk): _check.non_negative(f"{name}.{kk}", vv, where=where) for kk, vv in value.items()}
        raise AssertionError(k)


class Section:
    """A validated group of parameters; subclasses declare ``FIELDS``."""

    FIELDS: dict[str, Field] = {}
    TABLE = ""
    _where: str                     # "[table]" or the caller's context, for messages

    if TYPE_CHECKING:
        # The fields of FIELDS are instance attributes set (validated) in __init__ and
        # __setattr__; their types follow each Field's kind, so the checker sees Any.
        def __getattr__(self, name: str) -> Any: ...

    def __init__(self, values: dict | None = None, *, where: str = "") -> None:
        object.__setattr__(self, "_where", where or f"[{self.TABLE}]")
        values = dict(values or {})
        unknown = sorted(set(values) - set(self.FIELDS))
        if unknown:
            raise ConfigError(
                f"{self._where}: unknown key {unknown[0]!r}"
                f"{close_matches(unknown[0], self.FIELDS)}; allowed keys: {', '.join(self.FIELDS)}")
        for name, f in self.FIELDS.items():
            if name in values:
                setattr(self, name, values[name])
            elif f.required:
                raise ConfigError(f"{self._where}: missing field {name!r} ({f.doc or f.kind})")
            else:
                object.__setattr__(self, name, copy.deepcopy(f.default))

    def __setattr__(self, name, value):
        f = self.FIELDS.get(name)
        if f is None:
            raise ConfigError(f"{self._where}: unknown field {name!r}{close_matches(name, self.FIELDS)}; "
                              f"allowed: {', '.join(self.FIELDS)}")
        object.__setattr__(self, name, f.check(name, value, self._where))

    def to_dict(self) -> dict:
        return {k: copy.deepcopy(getattr(self, k)) for k in self.FIELDS}

    def __repr__(self):
        inner = ", ".join(f"{k}={getattr(self, k)!r}" for k in self.FIELDS)
        return f"{type(self).__name__}({inner})"

    def __eq__(self, other):
        return type(self) is type(other) and self.to_dict() == other.to_dict()


class Airframe(Section):
    TABLE = "airframe"
    FIELDS = {
        "mass_kg": Field("pos", doc="takeoff mass without payload", unit="kg",
                         bounds=(0.005, 50.0, "a 5 g nano drone to a 50 kg heavy-lift multirotor")),
        "arm_length_m": Field("pos", doc="centre to rotor axis", unit="m",
                              bounds=(0.01, 2.0, "centre to rotor axis, nano to heavy-lift frames")),
        "layout": Field("layout", "x"),
        "rotor_count": Field("rotors", 4),
        "inertia_kg_m2": Field("vec3pos", doc="principal moments Ixx Iyy Izz", unit="kg m^2",
                               bounds=(1e-7, 100.0, "principal moments of 5 g to 50 kg airframes")),
        "body_size_m": Field("vec3pos", doc="collision box L W H", unit="m",
                             bounds=(0.005, 5.0, "body box edges in metres, not millimetres")),
        "drag_area_m2": Field("vec3pos", doc="Cd*A along body x y z", unit="m^2",
                              bounds=(1e-5, 5.0, "Cd x area of a multirotor body")),
        "max_tilt_deg": Field("angle", 35.0, unit="deg"),
    }


class Rotor(Section):
    TABLE = "rotor"
    FIELDS = {
        "diameter_m": Field("pos", unit="m", bounds=(0.02, 1.6, "propellers from 20 mm to 63 in")),
        "thrust_coeff": Field("pos", doc="kf, N/(rad/s)^2"),
        "torque_coeff": Field("pos", doc="km, N m/(rad/s)^2"),
        "max_speed_rad_s": Field("pos", unit="rad/s",
                                 bounds=(50.0, 10000.0, "rad/s, not rpm: 480 to 95000 rpm")),
        "time_constant_s": Field("pos", unit="s",
                                 bounds=(0.002, 0.5, "motor and propeller spin-up, 2 ms to 0.5 s")),
        "blade_drag": Field("nonneg", BLADE_DRAG_DEFAULT,
                            bounds=(0.0, 0.05, "solidity x section drag, ~0.001 to 0.01"),
                            doc="sigma x Cd0 (rotor solidity times blade section drag) for the "
                                "rotor drag (H-force, airframe/rotor_drag.py); 0: none"),
    }

    @property
    def max_thrust_n(self) -> float:
        """Thrust of one rotor at full speed (N): kf * omega_max^2."""
        return self.thrust_coeff * self.max_speed_rad_s ** 2

    @property
    def disc_area_m2(self) -> float:
        return math.pi * (0.5 * self.diameter_m) ** 2


class Battery(Section):
    """Battery: capacity, nominal voltage, chemistry and cells, internal resistance,
    cut-off voltage, usable fraction and reserve level (an equivalent circuit,
    see ``energy/battery.py``)."""

    TABLE = "battery"
    FIELDS = {
        "capacity_mah": Field("pos", unit="mAh", bounds=(10.0, 100000.0, "mAh, 10 mAh to 100 Ah packs")),
        "voltage_v": Field("pos", doc="nominal (label) voltage", unit="V",
                           bounds=(1.0, 60.0, "1S to 14S lithium packs")),
        "chemistry": Field("chemistry", "lipo", doc="lipo or li-ion"),
        "cells": Field("cells", None, doc="cells in series; default: voltage_v / nominal cell voltage"),
        "internal_resistance_mohm": Field("optpos", None, unit="mOhm",
                                          bounds=(0.1, 2000.0, "per cell, high-rate to tiny cells"),
                                          doc="DC resistance of one cell at half charge; default: "
                                              "0.03 ohm Ah / capacity"),
        "cutoff_v_per_cell": Field("optpos", None, unit="V",
                                   bounds=(2.0, 3.9, "per cell, below the open-circuit voltage"),
                                   doc="terminal voltage under load that ends the flight; "
                                       "default: the chemistry's datasheet cut-off"),
        "usable_fraction": Field("frac01", 1.0, doc="share of the charge that can be drawn "
                                 "(the battery management system's 0 %)",
                                 bounds=(0.01, 1.0, "a pack that lets less than 1 % of its "
                                                    "charge be drawn cannot fly")),
        "reserve_fraction": Field("reserve", 0.15, doc="state of charge that triggers return home"),
    }

    @property
    def cell_count(self) -> int:
        if self.cells is not None:
            return self.cells
        return max(1, round(self.voltage_v / _cells.NOMINAL_V[self.chemistry]))

    @property
    def resistance_ohm(self) -> float:
        """DC resistance of one cell at half charge (ohm)."""
        if self.internal_resistance_mohm is not None:
            return self.internal_resistance_mohm * 1e-3
        return _cells.SPECIFIC_RESISTANCE_OHM_AH / (self.capacity_mah * 1e-3)

    @property
    def cutoff_v(self) -> float:
        """Cut-off voltage of one cell under load (V)."""
        c = self.cutoff_v_per_cell
        return _cells.CUTOFF_V[self.chemistry] if c is None else c

    @property
    def energy_j(self) -> float:
        """Usable chemical energy in joules: cells x capacity x the open-circuit voltage
        integrated from full charge down to 1 - usable_fraction."""
        return _cells.usable_energy_j(self.chemistry, self.cell_count, self.capacity_mah * 1e-3,
                                      1.0 - self.usable_fraction)

    def circuit(self) -> _cells.Circuit:
        """A fresh, full equivalent circuit of this pack for one flight."""
        return _cells.Circuit(chemistry=self.chemistry, cells=self.cell_count,
                              capacity_ah=self.capacity_mah * 1e-3, resistance_ohm=self.resistance_ohm,
                              cutoff_v_per_cell=self.cutoff_v)

    @property
    def nameplate_wh(self) -> float:
        return self.capacity_mah * self.voltage_v / 1000.0


class EnergyParams(Section):
    TABLE = "energy"
    FIELDS = {
        "figure_of_merit": Field("frac01", doc="hover figure of merit of one rotor"),
        "induced_power_factor": Field("pos", 1.15, doc="kappa >= 1"),
        "motor_efficiency": Field("frac01"),
        "esc_efficiency": Field("frac01"),
        "wake_interference": Field("nonneg", 0.0, doc="share of fore wake ingested by aft rotors"),
        "flight_controller_w": Field("nonneg", unit="W"),
        "io_w": Field("nonneg", 0.0, unit="W"),
        "sensors": Field("powers", {}, doc="sensor name = watts"),
        # the DC motor model, all four or none: with it the motors' efficiency is computed at
        # each operating point (energy/rotors.py Motors); a [datasheet] blueprint derives them
        "motor_kv_rpm_v": Field("optpos", None, unit="rpm/V", bounds=(10.0, 100000.0, "rpm per volt")),
        "motor_rm_ohm": Field("optpos", None, unit="ohm",
                              bounds=(0.0005, 1000.0, "winding resistance of any motor size")),
        "motor_i0_a": Field("optpos", None, unit="A", bounds=(0.0001, 20.0, "no-load current"),
                            doc="no-load current at motor_i0_rad_s"),
        "motor_i0_rad_s": Field("optpos", None, unit="rad/s", bounds=(1.0, 20000.0, "rotor speed"),
                                doc="the speed motor_i0_a is given at"),
    }


class Radio(Section):
    TABLE = "radio"
    FIELDS = {
        "tx_uj_per_byte": Field("nonneg"), "tx_uj_per_packet": Field("nonneg"),
        "rx_uj_per_byte": Field("nonneg"), "rx_uj_per_packet": Field("nonneg"),
        "idle_w": Field("nonneg", unit="W"),
        "bitrate_bps": Field("pos"),
        "heartbeat_period_s": Field("pos", 1.0, unit="s"),
        "heartbeat_bytes": Field("pos", 256, unit="B"),
    }


class Camera(Section):
    TABLE = "camera"
    FIELDS = {
        "width": Field("pixels", 320), "height": Field("pixels", 240),
        "fov_deg": Field("fov", 60.0, doc="vertical field of view"),
        "pitch_deg": Field("pitch", -90.0, doc="gimbal pitch, -90 = straight down"),
    }


class Sim(Section):
    TABLE = "sim"
    FIELDS = {
        "physics_hz": Field("pos", 500.0, unit="Hz", bounds=(10.0, 20000.0, "a physics step of 50 us to 0.1 s")),
        "control_hz": Field("pos", 100.0, unit="Hz",
                            bounds=(10.0, 8000.0, "flight-controller loop rates, 10 Hz to 8 kHz")),
    }
