"""Memoised computations: a costly, deterministic computation below the cache
layer (rendering a ``ViewSet``, scoring detections with COCOeval, a detector's
envelope) asks the memo store of the current context before computing::

    value = memo.recall("detection-kpis", inputs, compute, pack=..., unpack=...)

With no store open (the default outside pytest) that is ``compute()``. The flight
cache (``pytest_flockai.cache.caching``) opens one beside itself, in the same
directory and mode: ``inputs`` are keyed as a flight is (arrays and model files by
their bytes, objects by their class and attributes, your own code bypasses unless
marked ``cacheable``, plus the package source and library versions), and the
value is stored as ``pack(value)`` (plain JSON data and NumPy arrays) and read
back through ``unpack``. Only computations whose result is a pure function of
``inputs`` may be memoised.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from typing import Any, TypeVar

T = TypeVar("T")

_STORE: ContextVar = ContextVar("pytest_flockai_memo", default=None)


def _same(value: T) -> T:
    return value


def recall(kind: str, inputs: object, compute: Callable[[], T], *,
           pack: Callable[[T], Any] | None = None, unpack: Callable[[Any], T] | None = None) -> T:
    """``compute()``, or what the store of this context kept for ``kind`` and ``inputs``."""
    store = _STORE.get()
    if store is None:
        return compute()
    return store.recall(kind, inputs, compute, pack or _same, unpack or _same)


@contextmanager
def remembering(store: Any) -> Iterator[Any]:
    """Use ``store`` (an object with ``recall(kind, inputs, compute, pack, unpack)``,
    or None: compute everything) inside the block."""
    token = _STORE.set(store)
    try:
        yield store
    finally:
        _STORE.reset(token)


def active() -> Any:
    """The memo store of this context, or None."""
    return _STORE.get()


__all__ = ["active", "recall", "remembering"]
