"""Names that moved to another public home keep working at the old one.

A module lists its moved names with ``__getattr__ = moved(__name__, {old: new})``
(PEP 562): reading ``old`` there returns the object from its new home and warns once
per process (a ``DeprecationWarning`` naming the new home), so code written against
the old spelling keeps running while it is updated. Only names that left a module
go through here; a module that is simply internal (not in the API reference) is not
wrapped, its names are not promised at all."""

from __future__ import annotations

import warnings
from collections.abc import Callable
from importlib import import_module
from typing import Any

#: (module, name) already warned about in this process
_WARNED: set[tuple[str, str]] = set()


def moved(module: str, names: dict[str, str]) -> Callable[[str], Any]:
    """A module ``__getattr__`` for ``names``: old name -> the dotted path of its new
    public home (``"pytest_flockai.world.gimbal_pose"``)."""

    def __getattr__(name: str) -> Any:
        new = names.get(name)
        if new is None:
            raise AttributeError(f"module {module!r} has no attribute {name!r}")
        home, _, attr = new.rpartition(".")
        value = getattr(import_module(home), attr)
        if (module, name) not in _WARNED:
            _WARNED.add((module, name))
            warnings.warn(f"{module}.{name} moved to {new}; import it from there "
                          f"(the old name will be removed)", DeprecationWarning, stacklevel=2)
        return value

    return __getattr__
