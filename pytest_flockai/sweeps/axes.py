"""The axes of a sweep: named changes to a base mission, checked where they enter.

An axis name is one of

- ``mission_seed``: the mission's seed (an integer >= 0; the keyword ``seed``
  of ``fa.sweep`` is the seed of the random / Latin-hypercube sampling);
- ``wind_mps``: the mean wind's horizontal speed (m/s), ``wind_dir_deg``: the
  direction the air moves towards, degrees from +x towards +y (the base
  mission's vertical wind and gust settings are kept);
- ``until``: the mission's end (a number of simulated seconds, or ``"landed"``,
  ``"battery_depleted"``, ``"battery_reserve"``);
- any override ``fa.drone()`` accepts: ``payload_kg``, ``battery_mah``,
  ``battery_v``, ``physics_hz``, ``control_hz``, a field of a blueprint section
  (``mass_kg``, ``usable_fraction``) or ``section__field``
  (``battery__reserve_fraction``).

``apply(mission, values)`` returns a changed copy of the mission (the base is
never touched); ``check_value(name, value)`` applies one value alone to the
base, so a value no mission could take fails before anything flies.
"""

from __future__ import annotations

import copy
import hashlib
import math
import pickle
from numbers import Integral, Real

import numpy as np

from ..airframe.drone import derived_from_datasheet, resolve_override
from ..errors import ConfigError, close_matches
from ..mission.plan import check_until, resolve
from ..world.wind import Wind

MISSION_AXES = ("mission_seed", "wind_mps", "wind_dir_deg", "until")
#: axes whose values are whole numbers (a random range draws integers)
INTEGER_AXES = {"mission_seed"}


def allowed_text() -> str:
    return (f"{', '.join(MISSION_AXES)}, or a fa.drone() override (payload_kg, battery_mah, "
            f"battery_v, physics_hz, control_hz, a section field such as mass_kg, or "
            f"section__field)")


def check_name(name: str) -> None:
    """ConfigError for an axis name that is neither a mission axis nor a drone override."""
    if name in MISSION_AXES:
        return
    try:
        resolve_override(name)
    except ConfigError:
        known = list(MISSION_AXES) + ["payload_kg", "battery_mah", "battery_v", "physics_hz",
                                      "control_hz"]
        raise ConfigError(f"sweep: unknown axis {name!r}{close_matches(name, known)}; allowed: "
                          f"{allowed_text()}") from None


def _copy(base):
    """A deep copy of ``base``: a pickle round trip (several times faster than
    ``copy.deepcopy`` on a mission, and the process backend pickles missions anyway),
    else ``copy.deepcopy`` (a mission holding something that does not pickle)."""
    try:
        return pickle.loads(pickle.dumps(base, protocol=pickle.HIGHEST_PROTOCOL))
    except Exception:           # noqa: BLE001 - anything unpicklable: the slower deep copy
        return copy.deepcopy(base)


def apply(base, values: dict):
    """A copy of ``base`` (a Mission) with the axis values applied."""
    return resolved(base, values)[0]


def resolved(base, values: dict, share: bool = False, check_only: bool = False):
    """(mission, flight plan): ``apply``'s copy of ``base`` and its resolved plan.

    ``share=True``: a copy for reading only (the batched backend reads the plan's numbers):
    the mission object is copied shallowly and its drone deep only when an axis changes
    the drone (the pilot, wind, tasks ... are the base's own objects, which such a caller
    never flies); several times cheaper than the deep copy. ``check_only=True``
    (``check_value``, which drops the copy): the drone and the sections an axis changes
    copied shallowly too (nothing binds to that drone).
    """
    drone_axes = [name for name in values if name not in MISSION_AXES]
    if share or check_only:
        m, drone = base, base.drone
        if drone_axes:
            drone = _shallow(base.drone, drone_axes) if check_only else _copy(base.drone)
    else:
        m = _copy(base)
        drone = m.drone
    changes: dict = {}                  # the mission's own fields, set through replace below
    for name, value in values.items():
        if name == "mission_seed":
            if isinstance(value, bool) or not isinstance(value, Integral) or value < 0:
                raise ConfigError(f"mission_seed = {value!r} is not allowed; expected an "
                                  f"integer >= 0")
            changes["seed"] = int(value)
        elif name == "until":
            changes["until"] = check_until(value)
        elif name in ("wind_mps", "wind_dir_deg"):
            _number(name, value)
        elif drone.datasheet is not None and derived_from_datasheet(name):
            raise ConfigError(f"{name} = {value!r}: {drone.source} derives its rotors, motors "
                              f"and drag from [datasheet] values, and setting {name} on the built "
                              f"drone would not derive them again; allowed: sweep it as "
                              f"separate bases, fa.drone(..., {name}=...) each")
        else:
            section, field = resolve_override(name)
            target = drone if section is None else getattr(drone, section)
            if target is None:
                raise ConfigError(f"{name} = {value!r}: this blueprint has no [{section}] table")
            setattr(target, field, value)
    if "wind_mps" in values or "wind_dir_deg" in values:
        changes["wind"] = _wind(m.wind, values.get("wind_mps"), values.get("wind_dir_deg"))
    drone.check(f"sweep variant {values}")
    # the variant: a checked copy of the spec (live subscribers stay with the base mission)
    m = m.replace(drone=drone, **changes)
    return m, resolve(m)


def _shallow(drone, names):
    """A shallow copy of ``drone`` with its own copy of each section an axis in ``names``
    sets (the override's target); the other sections are the base's."""
    d = copy.copy(drone)
    for name in names:
        try:
            section = resolve_override(name)[0]
        except ConfigError:
            continue                    # an unknown name: ``resolved`` says what is wrong
        if section is not None and getattr(d, section) is not None:
            object.__setattr__(d, section, copy.copy(getattr(d, section)))
    return d


def _number(name, value) -> float:
    if isinstance(value, bool) or not isinstance(value, Real) or not math.isfinite(value):
        raise ConfigError(f"{name} = {value!r} is not allowed; expected a finite number")
    return float(value)


def _wind(base: Wind | None, speed, direction) -> Wind:
    mean = base.mean if base is not None else (0.0, 0.0, 0.0)
    if speed is None:
        speed = math.hypot(mean[0], mean[1])
    elif speed < 0:
        raise ConfigError(f"wind_mps = {speed!r} is not allowed; expected a speed >= 0 m/s")
    if direction is None:
        direction = math.degrees(math.atan2(mean[1], mean[0]))
    a = math.radians(direction)
    kw = ({} if base is None else {"gust_std": base.gust_std, "gust_tau_s": base.gust_tau_s})
    return Wind((speed * math.cos(a), speed * math.sin(a), mean[2]), **kw)


#: (digest of the base mission's pickle, axis, value) checked by earlier sweeps in this process: a
#: repeated sweep of the same base does not apply each value again
_PASSED: set = set()
_PASSED_MAX = 65536
_PLAIN = (int, float, str, bool, np.integer, np.floating, np.bool_)


def check_values(base, name: str, values) -> None:
    """``check_value`` for each distinct value of one axis, skipping plain values (numbers,
    strings) an earlier call checked on a base mission with the same pickle."""
    try:
        key = hashlib.sha256(pickle.dumps(base, protocol=pickle.HIGHEST_PROTOCOL)).digest()
    except Exception:           # noqa: BLE001 - not picklable: every value checked
        key = None
    for value in {repr(v): v for v in values}.values():
        memo = (key, name, type(value), repr(value)) if (
            key is not None and isinstance(value, _PLAIN)) else None
        if memo is not None and memo in _PASSED:
            continue
        check_value(base, name, value)
        if memo is not None:
            if len(_PASSED) >= _PASSED_MAX:
                _PASSED.clear()
            _PASSED.add(memo)


def check_value(base, name: str, value) -> None:
    """Apply one value of one axis alone to the base: a ConfigError names the axis,
    the value and what the mission allows."""
    try:
        resolved(base, {name: value}, check_only=True)
    except ConfigError as exc:
        raise ConfigError(f"sweep: axis {name} = {value!r} is not allowed: {exc}") from None
