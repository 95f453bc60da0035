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
"""

from __future__ import annotations

from contextlib import contextmanager
from contextvars import ContextVar

from .. import memo as _memo
from ..errors import ConfigError
from .auth import CacheKey, default_key
from .entry import NotAuthentic
from .key import Uncacheable, cacheable, flight_key, memo_key
from .memo import MemoStore
from .store import MODES, CacheMismatch, CacheWarning, CorruptEntry, FlightCache, Lookup

_ACTIVE: ContextVar[FlightCache | None] = ContextVar("pytest_flockai_flight_cache", default=None)


@contextmanager
def caching(cache: FlightCache | None):
    """Use ``cache`` for every ``Mission.run()`` and ``Fleet.run()`` inside the block,
    and its memo store for the memoised computations (``pytest_flockai.memo``:
    rendered views, detection scores, envelopes); None: no cache."""
    if cache is not None and not isinstance(cache, FlightCache):
        raise ConfigError(f"caching: cache = {cache!r} is not allowed; expected a FlightCache "
                          f"or None")
    token = _ACTIVE.set(cache)
    try:
        with _memo.remembering(cache.memo if cache is not None else None):
            yield cache
    finally:
        _ACTIVE.reset(token)


def active() -> FlightCache | None:
    return _ACTIVE.get()


def lookup(mission, result_type=None) -> Lookup | None:
    """The current cache's answer for ``mission`` (None when no cache is open); a
    ``Fleet`` passes its ``result_type`` (FleetResult)."""
    cache = _ACTIVE.get()
    if cache is None:
        return None
    return cache.lookup(mission) if result_type is None else cache.lookup(mission, result_type)


__all__ = [
    "MODES",
    "CacheKey",
    "CacheMismatch",
    "CacheWarning",
    "CorruptEntry",
    "FlightCache",
    "Lookup",
    "MemoStore",
    "NotAuthentic",
    "Uncacheable",
    "active",
    "cacheable",
    "caching",
    "default_key",
    "flight_key",
    "lookup",
    "memo_key",
]
