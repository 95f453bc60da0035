"""A policy's reserved names: the methods the flight loop calls on every
policy (``step``, ``finish``, ``kpis``, ``bind``, ...). A subclass that stores data
under one of them (``self.step = 0``, ``self.kpis = {}``, or a class attribute
``finish = True``) would make the loop call a number: refused where it is written, with
a ``ConfigError`` naming the attribute, the value and the names to avoid."""

from __future__ import annotations

import inspect

from ..errors import ConfigError


def reserved(base: type) -> tuple:
    """The public and private method names of ``base`` and its bases (not dunders)."""
    names: set[str] = set()
    for k in base.__mro__:
        if k is object:
            continue
        names.update(n for n, v in vars(k).items()
                     if not n.startswith("__") and (inspect.isfunction(v) or isinstance(v, property)))
    return tuple(sorted(names))


def _message(owner: str, label: str, name: str, value, names) -> str:
    shown = ", ".join(n for n in names if not n.startswith("_"))
    return (f"{owner}: {label} = {value!r} is not allowed: {name!r} is a reserved name of "
            f"fa.Policy (the flight loop calls it); reserved: {shown}; store it under another "
            f"name, e.g. {name + '_'!r} or {'my_' + name!r}")


def check_class(cls: type, names) -> None:
    """A subclass may override a reserved method with a function, not with data."""
    for n in names:
        if n in vars(cls):
            v = vars(cls)[n]
            if not (callable(v) or isinstance(v, (property, staticmethod, classmethod))):
                raise ConfigError(_message(f"class {cls.__name__}", n, n, v, names))


def check_attr(obj, name: str, value, names) -> None:
    """An instance attribute may not shadow a reserved method."""
    if name in names:
        raise ConfigError(_message(f"policy {type(obj).__name__}", f"self.{name}", name, value,
                                   names))
