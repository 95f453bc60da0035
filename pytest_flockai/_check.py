"""Small argument validators: each raises ConfigError naming field and value.

``value`` is typed ``Any``: it is what the user passed, checked here.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Collection
from numbers import Real
from typing import Any, TypeVar

from .errors import ConfigError, close_matches

T = TypeVar("T")


def _where(where: str) -> str:
    return f"{where}: " if where else ""


def number(field: str, value: Any, *, where: str = "", minimum: float | None = None,
           maximum: float | None = None, min_inclusive: bool = True,
           max_inclusive: bool = True) -> float:
    """A finite real number within optional bounds, returned as float."""
    if isinstance(value, bool) or not isinstance(value, Real):
        raise ConfigError(f"{_where(where)}{field} = {value!r} is not a number; "
                          f"expected a finite real number")
    v = float(value)
    if not math.isfinite(v):
        raise ConfigError(f"{_where(where)}{field} = {value!r} is not finite; "
                          f"expected a finite real number")
    if minimum is not None:
        bad = v < minimum if min_inclusive else v <= minimum
        if bad:
            op = ">=" if min_inclusive else ">"
            rng = f"{op} {minimum:g}" + (f" and <= {maximum:g}" if maximum is not None else "")
            raise ConfigError(f"{_where(where)}{field} = {value!r} is out of range; allowed: {rng}")
    if maximum is not None:
        bad = v > maximum if max_inclusive else v >= maximum
        if bad:
            op = "<=" if max_inclusive else "<"
            lo = f"{minimum:g} .. " if minimum is not None else ""
            raise ConfigError(f"{_where(where)}{field} = {value!r} is out of range; "
                              f"allowed: {lo}{op} {maximum:g}")
    return v


def positive(field: str, value: Any, *, where: str = "") -> float:
    """A finite number > 0, as float."""
    return number(field, value, where=where, minimum=0.0, min_inclusive=False)


def non_negative(field: str, value: Any, *, where: str = "") -> float:
    """A finite number >= 0, as float."""
    return number(field, value, where=where, minimum=0.0)


def fraction(field: str, value: Any, *, where: str = "", allow_zero: bool = True,
             allow_one: bool = True) -> float:
    """A number in [0, 1] (ends excluded when not allowed), as float."""
    return number(field, value, where=where, minimum=0.0, maximum=1.0,
                  min_inclusive=allow_zero, max_inclusive=allow_one)


def vector(field: str, value: Any, n: int, *, where: str = "",
           positive_entries: bool = False) -> tuple[float, ...]:
    """A sequence of ``n`` finite numbers (each > 0 with ``positive_entries``)."""
    try:
        items = tuple(value)
    except TypeError:
        raise ConfigError(f"{_where(where)}{field} = {value!r} is not a sequence; "
                          f"expected {n} numbers") from None
    if len(items) != n:
        raise ConfigError(f"{_where(where)}{field} = {value!r} has {len(items)} entries; "
                          f"expected {n} numbers")
    check = positive if positive_entries else number
    return tuple(check(f"{field}[{i}]", x, where=where) for i, x in enumerate(items))


def choice(field: str, value: T, allowed: Collection, *, where: str = "") -> T:
    """``value`` itself when it is one of ``allowed``."""
    if value not in allowed:
        raise ConfigError(f"{_where(where)}{field} = {value!r} is not allowed; "
                          f"allowed: {', '.join(map(repr, allowed))}"
                          f"{close_matches(str(value), [str(a) for a in allowed])}")
    return value


def area(value: Any, *, where: str) -> tuple[float, float, float, float]:
    """A box ((x0, y0), (x1, y1)) of finite numbers with both sides longer than 0,
    returned as floats (x0, y0, x1, y1) in the order given."""
    try:
        (x0, y0), (x1, y1) = value
    except (TypeError, ValueError):
        raise ConfigError(f"{_where(where)}area = {value!r} is not ((x0, y0), (x1, y1))") from None
    x0, y0, x1, y1 = (number(n, v, where=where) for n, v in
                      (("area x0", x0), ("area y0", y0), ("area x1", x1), ("area y1", y1)))
    if abs(x1 - x0) < 1e-6 or abs(y1 - y0) < 1e-6:
        raise ConfigError(f"{_where(where)}area = {value!r} is degenerate; both sides must be "
                          f"longer than 0")
    return x0, y0, x1, y1


def overrides(obj: object, base: type, method: str, hint: str = "") -> None:
    """ConfigError when ``obj``'s class does not define ``base``'s abstract ``method``
    (an interface method left as ``base`` has it), e.g. a Policy without ``decide``."""
    if getattr(type(obj), method, None) is getattr(base, method):
        raise ConfigError(f"{type(obj).__name__}: a {base.__name__} needs a {method}{hint} "
                          f"method; define it in the subclass")


def replace(spec: Any, where: str, changes: dict) -> Any:
    """``dataclasses.replace`` of a frozen spec (Mission, Fleet, FleetDrone), so checked
    again like a new one; an unknown field is a ConfigError naming it and the allowed."""
    known = [f.name for f in dataclasses.fields(spec) if f.init]
    for k in changes:
        if k not in known:
            raise ConfigError(f"{where}.replace: {k} is not a {where} field"
                              f"{close_matches(k, known)}; allowed: {', '.join(known)}")
    return dataclasses.replace(spec, **changes)


class FrozenSpec:
    """A class that is not a dataclass (a sensor with per-flight state) but whose
    constructor's arguments, ``SPEC``, are frozen like a Mission's fields once
    ``_freeze()`` ran at the end of ``__init__``: assigning one raises, and
    ``replace(**changes)`` builds a new object, checked again by the constructor."""

    SPEC: tuple[str, ...] = ()

    def __setattr__(self, name: str, value: Any) -> None:
        if name in self.SPEC and self.__dict__.get("_frozen"):
            raise dataclasses.FrozenInstanceError(
                f"cannot assign to field {name!r}: a {type(self).__name__} is a frozen spec; "
                f".replace({name}=...) returns a checked copy")
        object.__setattr__(self, name, value)

    def _freeze(self) -> None:
        object.__setattr__(self, "_frozen", True)

    def _spec_value(self, name: str) -> Any:
        """The argument that gives ``name`` back to the constructor (override to convert)."""
        return getattr(self, name)

    def replace(self, **changes: Any) -> Any:
        """A copy with ``changes`` (argument=value), checked again like a new one."""
        where = type(self).__name__
        for k in changes:
            if k not in self.SPEC:
                raise ConfigError(f"{where}.replace: {k} is not a {where} field"
                                  f"{close_matches(k, self.SPEC)}; allowed: {', '.join(self.SPEC)}")
        return type(self)(**{n: self._spec_value(n) for n in self.SPEC} | changes)
