"""The Drone: a blueprint's parameters, validated, plus its energy model.

``drone("dji-mavic-2-pro")`` reads a TOML blueprint shipped with the package
(or a user's own file) and returns a fresh, independent ``Drone``. Every field
can be changed afterwards (``d.battery.capacity_mah = 4500``); every change is
validated where it is made.
"""

from __future__ import annotations

import copy
import math
import tomllib
from importlib import resources
from pathlib import Path

from .. import _check
from ..compute import Device
from ..compute.latency import device_value
from ..compute.runtimes import check_names
from ..energy import EnergyModel
from ..energy import battery as _cells
from ..energy.factory import carry_computer
from ..errors import ConfigError, close_matches
from ..physics import RHO_SEA_LEVEL, G  # G re-exported: airframe.drone.G
from ..sensors import Sensor
from .datasheet import Datasheet
from .datasheet import expand as _expand_datasheet
from .params import Airframe, Battery, Camera, EnergyParams, Radio, Rotor, Sim

MIN_THRUST_TO_WEIGHT = 1.3

_TOP_KEYS = {"name", "description", "datasheet", "airframe", "rotor", "battery", "energy", "radio",
             "compute", "sensors", "camera", "sim"}

# keyword overrides accepted by drone(): alias -> (section attribute, field)
_ALIASES = {
    "battery_mah": ("battery", "capacity_mah"),
    "battery_v": ("battery", "voltage_v"),
    "payload_kg": (None, "payload_kg"),
    "device": (None, "device"),
    "runtime": (None, "runtime"), "precision": (None, "precision"),
    "target": (None, "target"), "threads": (None, "threads"),
    "physics_hz": ("sim", "physics_hz"),
    "control_hz": ("sim", "control_hz"),
}
_DEPLOY = ("runtime", "precision", "target", "threads")
_SECTIONS = {"airframe": Airframe, "rotor": Rotor, "battery": Battery, "radio": Radio,
             "camera": Camera, "sim": Sim}


def _blueprint_dir():
    return resources.files("pytest_flockai.airframe") / "blueprints"


def blueprints() -> list[str]:
    """Names of the built-in drone blueprints."""
    return sorted(p.name[:-5] for p in _blueprint_dir().iterdir() if p.name.endswith(".toml"))


class Drone:
    """A simulated drone built from a blueprint.

    Attributes: ``name``, ``airframe``, ``rotor``, ``battery``, ``radio``,
    ``camera`` (or None), ``sim`` (physics and control rates), ``device``
    (on-board computer profile name or "none"; ``computer`` is its profile: set ``device``
    to a ``Device`` of your own, ``fa.compute.computer``, and it holds that one's name),
    ``sensors`` (names), ``payload_kg`` and ``energy`` (the composable energy model).
    """

    _computer: Device | None

    def __init__(self, data: dict, *, source: str = "<dict>") -> None:
        where = source
        unknown = sorted(set(data) - _TOP_KEYS)
        if unknown:
            raise ConfigError(f"{where}: unknown key {unknown[0]!r}{close_matches(unknown[0], _TOP_KEYS)}; "
                              f"allowed top-level keys: {', '.join(sorted(_TOP_KEYS))}")
        data, derived = _expand_datasheet(data, where)
        for req in ("name", "airframe", "rotor", "battery", "energy"):
            if req not in data:
                raise ConfigError(f"{where}: missing table or key {req!r}")
        object.__setattr__(self, "_ready", False)
        self.source = source
        #: figures derived from a [datasheet] table (C_T, C_P, FM, motor values), or None
        self.datasheet = derived
        self.name = _check_str("name", data["name"], where)
        self.description = str(data.get("description", ""))
        self.airframe = Airframe(data["airframe"], where=f"{where} [airframe]")
        self.rotor = Rotor(data["rotor"], where=f"{where} [rotor]")
        self.battery = Battery(data["battery"], where=f"{where} [battery]")
        self.radio = Radio(data.get("radio", {"tx_uj_per_byte": 0, "tx_uj_per_packet": 0,
                                               "rx_uj_per_byte": 0, "rx_uj_per_packet": 0,
                                               "idle_w": 0, "bitrate_bps": 1e6}),
                           where=f"{where} [radio]")
        self.camera = Camera(data["camera"], where=f"{where} [camera]") if "camera" in data else None
        self.sim = Sim(data.get("sim", {}), where=f"{where} [sim]")
        compute = data.get("compute", {})
        _no_unknown(compute, {"device", *_DEPLOY}, f"{where} [compute]")
        self.device = compute.get("device", "none")
        for k in _DEPLOY:       # the on-board tasks' default runtime, precision, target, threads
            setattr(self, k, compute.get(k))
        sensors = data.get("sensors", {})
        _no_unknown(sensors, {"names"}, f"{where} [sensors]")
        names = sensors.get("names", [])
        if not isinstance(names, list) or not all(isinstance(n, str) and n for n in names):
            raise ConfigError(f"{where} [sensors]: names = {names!r} is not allowed; expected a list "
                              f"of sensor names, e.g. names = [\"gps\", \"imu\"] (a string would be "
                              f"read one character at a time)")
        self.sensors = list(names)
        self.payload_kg = 0.0
        self.extra_sensors: list = []
        energy = EnergyParams(data["energy"], where=f"{where} [energy]")
        self.energy = EnergyModel.from_params(energy, device=self.computer, radio=self.radio)
        object.__setattr__(self, "_ready", True)
        self.check(where)

    def __setattr__(self, name, value):
        if name == "payload_kg":
            value = _check.non_negative("payload_kg", value, where=self.name)
        elif name == "device":
            value, computer = device_value(value, getattr(self, "name", ""))
            object.__setattr__(self, "_computer", computer)
            if getattr(self, "_ready", False):     # its idle and busy power from now on
                carry_computer(self.energy, computer)
        elif name in _DEPLOY:
            check_names(**{name: value}, where=getattr(self, "name", ""))
        elif name in _SECTIONS and not isinstance(value, _SECTIONS[name]) and not (
                value is None and name == "camera"):          # only the camera is optional
            raise ConfigError(f"{self.name}: {name} = {value!r} is not allowed; expected a "
                              f"{_SECTIONS[name].__name__} section"
                              f"{' or None' if name == 'camera' else ''}")
        object.__setattr__(self, name, value)

    @property
    def computer(self) -> Device | None:
        """The on-board computer's profile (None: ``device = "none"``): a profile of the
        package by its name, or the ``Device`` given (a team's own datasheet,
        ``fa.compute.computer``; a measured profile)."""
        return self._computer

    # derived quantities -------------------------------------------------
    @property
    def mass_kg(self) -> float:
        """Total mass: airframe plus payload."""
        return self.airframe.mass_kg + self.payload_kg

    @property
    def max_thrust_n(self) -> float:
        """Thrust of all rotors at full speed at sea level (N)."""
        return self.airframe.rotor_count * self.rotor.max_thrust_n

    @property
    def thrust_to_weight(self) -> float:
        """Maximum thrust over weight at sea level, payload included."""
        return self.max_thrust_n / (self.mass_kg * G)

    def thrust_to_weight_at(self, rho: float) -> float:
        """Thrust-to-weight in air of density ``rho`` (kg/m^3): thrust scales with rho."""
        return self.thrust_to_weight * rho / RHO_SEA_LEVEL

    def max_payload_kg(self, rho: float = RHO_SEA_LEVEL) -> float:
        """The largest payload that keeps the minimum thrust-to-weight in air of density rho."""
        return max(0.0, self.max_thrust_n * rho / RHO_SEA_LEVEL / (MIN_THRUST_TO_WEIGHT * G)
                   - self.airframe.mass_kg)

    @property
    def hover_thrust_per_rotor_n(self) -> float:
        """Thrust each rotor gives in a hover (N), payload included."""
        return self.mass_kg * G / self.airframe.rotor_count

    def rotor_layout(self) -> list[tuple[float, float, float]]:
        """(x, y, spin) per rotor in the body frame (x forward, y left).

        Rotors sit at angles (i + 1/2) * 360 / n from the nose, counter-clockwise
        seen from above; spin alternates, +1 for a counter-clockwise propeller
        (whose reaction torque on the body is clockwise, -z).
        """
        n, r = self.airframe.rotor_count, self.airframe.arm_length_m
        out = []
        for i in range(n):
            a = (i + 0.5) * 2.0 * math.pi / n
            out.append((r * math.cos(a), r * math.sin(a), 1.0 if i % 2 == 0 else -1.0))
        return out

    def add_sensor(self, sensor: Sensor) -> Drone:
        """Attach a sensor (paper Listing 2: ``mydrone.addSensor(temp)``): a
        ``fa.sensors`` object or a Sensor subclass. It is read at its rate in every
        flight and its power is added to the energy model's ``proc.sensors``."""
        if not isinstance(sensor, Sensor):
            raise ConfigError(f"{self.name}: add_sensor({sensor!r}): expected a Sensor "
                              f"(fa.sensors.GPS(), TemperatureSensor(...), a Sensor subclass)")
        names = {getattr(s, "name", None) for s in self.extra_sensors} | set(self.sensors)
        if sensor.name in names:
            raise ConfigError(f"{self.name}: a sensor named {sensor.name!r} is already on the drone; "
                              f"give it another name")
        self.extra_sensors.append(sensor)
        return self

    addSensor = add_sensor

    def check(self, where: str | None = None, *, rho: float = RHO_SEA_LEVEL) -> None:
        """Cross-field checks (thrust-to-weight in air of density ``rho``); run again
        before every flight."""
        where = where or self.source
        b = self.battery
        if b.cells is not None and not 3.0 <= b.voltage_v / b.cells <= 4.4:
            raise ConfigError(
                f"{where} [battery]: voltage_v = {b.voltage_v:g} V over cells = {b.cells} is "
                f"{b.voltage_v / b.cells:.2f} V per cell; allowed: 3.0 to 4.4 V per cell "
                f"(a {b.chemistry} pack's nominal voltage is cells x {_cells.NOMINAL_V[b.chemistry]} V)")
        tw = self.thrust_to_weight_at(rho)
        air = "" if rho == RHO_SEA_LEVEL else f" in air of {rho:.3f} kg/m^3"
        if not tw >= MIN_THRUST_TO_WEIGHT:
            raise ConfigError(
                f"{where}: thrust-to-weight{air} = {tw:.2f} (max thrust "
                f"{self.max_thrust_n * rho / RHO_SEA_LEVEL:.3g} N "
                f"for {self.mass_kg:.3g} kg incl. payload {self.payload_kg:g} kg) is below the "
                f"minimum {MIN_THRUST_TO_WEIGHT}; raise [rotor] max_speed_rad_s or thrust_coeff, "
                f"or lower the mass")

    def copy(self) -> Drone:
        """An independent deep copy (change it without touching this one)."""
        return copy.deepcopy(self)

    def to_dict(self) -> dict:
        """JSON-ready description, as it goes into a flight's scenario."""
        return {
            "name": self.name, "source": self.source, "payload_kg": self.payload_kg,
            "mass_kg": self.mass_kg, "device": self.device,
            **{k: getattr(self, k) for k in _DEPLOY if getattr(self, k) is not None},
            "sensors": list(self.sensors) + [s.name for s in self.extra_sensors],
            "airframe": self.airframe.to_dict(), "rotor": self.rotor.to_dict(),
            "battery": self.battery.to_dict(), "sim": self.sim.to_dict(),
            "energy": self.energy.describe(),
        }

    def __repr__(self):
        return (f"Drone({self.name!r}, mass={self.mass_kg:.3f} kg, "
                f"battery={self.battery.capacity_mah:g} mAh, device={self.device!r})")


def _check_str(field, value, where):
    if not isinstance(value, str) or not value:
        raise ConfigError(f"{where}: {field} = {value!r} is not allowed; expected a non-empty string")
    return value


def _no_unknown(table, allowed, where):
    if not isinstance(table, dict):
        raise ConfigError(f"{where}: expected a table, got {table!r}")
    extra = sorted(set(table) - set(allowed))
    if extra:
        raise ConfigError(f"{where}: unknown key {extra[0]!r}; allowed keys: {', '.join(sorted(allowed))}")


def load_blueprint(path: str | Path) -> dict:
    p = Path(path)
    try:
        with open(p, "rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise ConfigError(f"blueprint file {str(p)!r} does not exist") from None
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"blueprint file {str(p)!r} is not valid TOML: {exc}") from None
    except UnicodeDecodeError as exc:
        raise ConfigError(f"blueprint file {str(p)!r} is not UTF-8 text (byte {exc.object[exc.start]:#04x} "
                          f"at offset {exc.start}); allowed: a UTF-8 TOML file") from None
    except OSError as exc:     # a folder, no permission, ...
        raise ConfigError(f"blueprint file {str(p)!r} cannot be read: {exc.strerror or exc}; "
                          f"expected a readable TOML file") from None


def drone(name_or_path: str | Path, **overrides) -> Drone:
    """A fresh Drone from a built-in blueprint name or a path to a TOML file.

    Keyword overrides: ``battery_mah``, ``battery_v``, ``payload_kg``,
    ``device``, ``physics_hz``, ``control_hz``, or any field name of a section
    (``mass_kg=1.0``, ``usable_fraction=0.9``) or ``section__field``. On a blueprint
    with a ``[datasheet]`` table, its fields (``mass_kg``, ``prop_diameter_in``,
    ``motor_kv``...) and the pack voltage are set before the derivation, so everything
    that depends on them is derived again; ``payload_kg`` is the same drone carrying more.
    """
    s = str(name_or_path)
    if s.endswith(".toml") or "/" in s or "\\" in s:
        data, source = load_blueprint(s), s
    else:
        names = blueprints()
        if s not in names:
            raise ConfigError(f"unknown blueprint {s!r}{close_matches(s, names)}; "
                              f"available: {', '.join(names)} (or a path to a .toml file)")
        with (_blueprint_dir() / f"{s}.toml").open("rb") as fh:
            data, source = tomllib.load(fh), f"blueprint {s!r}"
    if "datasheet" in data:
        data, overrides = _datasheet_overrides(data, overrides)
    else:
        _no_datasheet_fields(overrides, source)
    d = Drone(data, source=source)
    for key, value in overrides.items():
        section, field = resolve_override(key)
        target = d if section is None else getattr(d, section)
        if target is None:
            raise ConfigError(f"{source}: override {key}={value!r} needs a [{section}] table, "
                              f"which this blueprint does not have")
        setattr(target, field, value)
    d.check(source)
    return d


#: override names of the pack voltage (on a datasheet blueprint it sets the motor model)
PACK_VOLTAGE_KEYS = ("battery_v", "voltage_v", "battery__voltage_v")


def derived_from_datasheet(key: str) -> bool:
    """Whether override ``key`` is one a ``[datasheet]`` derivation depends on (its own
    fields, the pack voltage): on such a drone it takes effect only through ``drone()``."""
    field = key[len("datasheet__"):] if key.startswith("datasheet__") else key
    return field in Datasheet.FIELDS or key in PACK_VOLTAGE_KEYS


def _datasheet_overrides(data: dict, overrides: dict):
    """(blueprint dict, remaining overrides): the overrides a [datasheet] derivation depends
    on (its own fields; the pack voltage, which sets the motor model) written into the
    tables before the Drone is built, so they are derived again."""
    data = {k: (dict(v) if isinstance(v, dict) else v) for k, v in data.items()}
    rest = {}
    for key, value in overrides.items():
        field = key[len("datasheet__"):] if key.startswith("datasheet__") else key
        if field in Datasheet.FIELDS and (field == key or key.startswith("datasheet__")):
            data["datasheet"][field] = value
        elif key in PACK_VOLTAGE_KEYS and isinstance(data.get("battery"), dict):
            data["battery"]["voltage_v"] = value
        elif key.startswith("datasheet__"):
            raise ConfigError(f"drone(): unknown override {key!r}{close_matches(field, Datasheet.FIELDS)}; "
                              f"allowed [datasheet] fields: {', '.join(Datasheet.FIELDS)}")
        else:
            rest[key] = value
    return data, rest


def _no_datasheet_fields(overrides: dict, source: str):
    for key, value in overrides.items():
        explicit = key.startswith("datasheet__")
        field = key[len("datasheet__"):] if explicit else key
        if explicit or (field in Datasheet.FIELDS
                        and not any(field in c.FIELDS for c in _SECTIONS.values())):
            raise ConfigError(f"{source}: override {key}={value!r} is a [datasheet] field, and this "
                              f"blueprint has no [datasheet] table to derive from; allowed: the "
                              f"fields of its own tables (airframe, rotor, battery, ...), e.g. "
                              f"mass_kg, thrust_coeff, diameter_m")


def resolve_override(key: str):
    """(section, field) of a ``fa.drone()`` override name (an alias such as ``mass_kg``, or
    ``section__field``); a ConfigError with did-you-mean hints for an unknown one."""
    if key in _ALIASES:
        return _ALIASES[key]
    if "__" in key:
        section, field = key.split("__", 1)
        if section in _SECTIONS and field in _SECTIONS[section].FIELDS:
            return section, field
    hits = [sec for sec, cls in _SECTIONS.items() if key in cls.FIELDS]
    if len(hits) == 1:
        return hits[0], key
    allowed = sorted(set(_ALIASES) | {f for c in _SECTIONS.values() for f in c.FIELDS})
    raise ConfigError(f"drone(): unknown override {key!r}{close_matches(key, allowed)}; "
                      f"allowed: {', '.join(allowed)} or section__field")
