"""The flight cache: a completed FlightResult reused when nothing that shapes it
changed (see ``key.py`` for what the key covers, ``store.py`` for the files).

``Mission.run()`` and ``Fleet.run()`` ask the cache of the current context, if one
is open (a fleet is keyed by every drone's full scenario and the fleet's own
settings: pads, area, swath, offload)::

    from pytest_flockai.cache import FlightCache, caching
    with caching(FlightCache(".flights")):
        r = fa.Mission(...).run()        # flown and stored, or read back

The pytest plugin opens one per test under pytest's cache directory
(``--flockai-cache``). A result read from the cache compares equal to the one
flown (KPIs, telemetry, events, probe samples); ``result.cache`` says where it
came from (``{"status": "hit" | "stored" | "flown" | "bypass" | "replaced" | "verified",
...}``). Entries are authenticated with an HMAC (``auth.py``: ``FLOCKAI_CACHE_KEY``)
and read within limits (``entry.py``); docs/how-to/ci-cache.md has the threat model.
came from (``{"status": "hit" | "stored" | "flown" | "bypass" | "replaced", ...}``).

Importing this package is cheap (the pytest plugin opens a cache around every
test, also tests that fly nothing): the store, the keys and the memo store
(NumPy, pandas) load on first use, and the plugin opens a ``Deferred`` cache,
which builds its ``FlightCache`` when a flight or a memoised computation first asks.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from importlib import import_module as _import_module
from typing import TYPE_CHECKING, Any

from .. import memo as _memo
from ..errors import ConfigError
from .modes import MODES, VERIFY_FRACTION

if TYPE_CHECKING:      # loaded on first use (see _LAZY)
    from .store import FlightCache, Lookup


#: public name -> its module in this package, imported on first use
_LAZY = {"CacheWarning": ".store", "CorruptEntry": ".store", "FlightCache": ".store",
         "Lookup": ".store", "MemoStore": ".memo_store", "Uncacheable": ".key", "cacheable": ".key",
         "flight_key": ".key", "memo_key": ".key", "CacheKey": ".auth", "default_key": ".auth",
         "NotAuthentic": ".entry", "CacheMismatch": ".store"}

_ACTIVE: ContextVar = ContextVar("pytest_flockai_flight_cache", default=None)


class Deferred:
    """A flight cache opened on first use: ``FlightCache(directory, mode)`` is built
    (its store, NumPy and pandas loaded) when a flight or a memoised computation of
    the context first asks; a context that asks nothing loads nothing."""

    def __init__(self, directory: str | os.PathLike, mode: str = "readwrite",
                 **options: Any) -> None:
        if mode not in MODES:
            raise ConfigError(f"FlightCache: mode = {mode!r} is not allowed; allowed: "
                              f"{', '.join(MODES)}")
        self.directory, self.mode, self.options = directory, mode, options
        self._cache: FlightCache | None = None

    def open(self) -> FlightCache:
        """The ``FlightCache`` (built on the first call, with the options given)."""
        if self._cache is None:
            self._cache = __getattr__("FlightCache")(self.directory, self.mode, **self.options)
        return self._cache

    def recall(self, kind: str, inputs: object, compute: Callable[[], Any],
               pack: Callable[[Any], Any], unpack: Callable[[Any], Any]) -> Any:
        """The memo store's ``recall`` (``pytest_flockai.memo``), through the opened cache."""
        return self.open().memo.recall(kind, inputs, compute, pack, unpack)


def _is_flight_cache(cache: object) -> bool:
    store = sys.modules.get(f"{__name__}.store")      # never loaded: no FlightCache exists
    return store is not None and isinstance(cache, store.FlightCache)


@contextmanager
def caching(cache: FlightCache | Deferred | None) -> Iterator[FlightCache | Deferred | None]:
    """Use ``cache`` (a ``FlightCache``, a ``Deferred`` one, or None: no cache) for
    every ``Mission.run()`` and ``Fleet.run()`` inside the block, and its memo store
    for the memoised computations (``pytest_flockai.memo``: rendered views,
    detection scores, envelopes)."""
    if cache is not None and not isinstance(cache, Deferred) and not _is_flight_cache(cache):
        raise ConfigError(f"caching: cache = {cache!r} is not allowed; expected a FlightCache "
                          f"or None")
    token = _ACTIVE.set(cache)
    try:
        memo = cache if isinstance(cache, Deferred) or cache is None else cache.memo
        with _memo.remembering(memo):
            yield cache
    finally:
        _ACTIVE.reset(token)


def active() -> FlightCache | None:
    """The ``FlightCache`` of this context (a deferred one opened now), or None."""
    cache = _ACTIVE.get()
    return cache.open() if isinstance(cache, Deferred) else cache


def lookup(mission: object, result_type: type | None = None) -> Lookup | None:
    """The current cache's answer for ``mission`` (None when no cache is open); a
    ``Fleet`` passes its ``result_type`` (FleetResult)."""
    cache = active()
    if cache is None:
        return None
    return cache.lookup(mission) if result_type is None else cache.lookup(mission, result_type)


def __getattr__(name: str):
    """The store's, the keys' and the memo store's names, imported on first use."""
    if name not in _LAZY:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(_import_module(_LAZY[name], __name__), name)
    globals()[name] = value
    return value


__all__ = ["CacheKey", "CacheMismatch", "CacheWarning", "CorruptEntry", "Deferred", "FlightCache",
           "Lookup", "MODES", "MemoStore", "NotAuthentic", "Uncacheable", "VERIFY_FRACTION",
           "active", "cacheable", "caching", "default_key", "flight_key", "lookup", "memo_key"]
