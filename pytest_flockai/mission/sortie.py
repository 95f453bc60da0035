"""The one run path of a ``Mission`` and a ``Fleet``: the open flight cache's answer if it
has one; else build the flight, fly it, collect the result (on a ``SimulationError``, the
partial result, carried on the error), store it in the cache and publish it to the
recording sink. A Mission and a Fleet differ only in what they build and collect (a
``Sortie``), so the steps and their order (store before publish: a test's derived KPIs
stay out of the cache) are written once."""

from __future__ import annotations

import time as _time
from collections.abc import Callable, Sequence
from typing import Any, Protocol

from .. import cache as _cache
from ..errors import SimulationError
from ..recording import publish
from . import loop
from .assemble import Flight


class Sortie(Protocol):
    """One flight of a spec, built: what ``loop.fly`` flies and how its result is made."""

    flight: Flight
    #: flight-wide steps after the drones' components (``loop.fly``'s ``steps``)
    steps: Sequence

    def finished(self, wall_s: float) -> Any:
        """The result of the flight flown to its end."""

    def stopped(self, exc: SimulationError, wall_s: float) -> Any:
        """The result so far of a flight stopped by ``exc``."""


def run(spec: object, build: Callable[[Any], Sortie], result_type: type | None = None) -> Any:
    """Fly ``spec`` (a Mission or a Fleet) through ``build(spec) -> Sortie`` and return its
    result, or take it from the open flight cache (``result_type``: the type to decode it as,
    None for a single flight's ``FlightResult``)."""
    found = _cache.lookup(spec, result_type)
    if found is not None and found.result is not None:
        taken = getattr(spec, "taken_from_cache", None)
        if taken is not None:           # what flying it leaves on your objects (a Fleet's)
            taken(found.result)
        publish(found.result, spec)
        return found.result
    wall0 = _time.perf_counter()
    sortie = build(spec)
    try:
        loop.fly(sortie.flight, sortie.steps)
    except SimulationError as exc:
        exc.result = sortie.stopped(exc, _time.perf_counter() - wall0)
        publish(exc.result, spec)
        raise
    res = sortie.finished(_time.perf_counter() - wall0)
    if found is not None and found.status != "off":
        found.store(res)                # before publish: derived KPIs of a test stay out
    publish(res, spec)
    return res
