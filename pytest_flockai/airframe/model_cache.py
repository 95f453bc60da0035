"""Compiled MuJoCo models of flights, built once per world and drones and reused.

Compiling a world's model is the slow part of building a flight (2 ms for the
empty ground, ~0.1 s for an urban world of 500 people, ~1 s for 3,000: the
figures' meshes), and every flight over the same world with the same drones
compiles the same model. ``compiled`` keeps the compiled models of this
process, keyed on the world's content (``World.fingerprint``: two worlds built
alike share an entry, a world edited in between gets a new one) and on the
exact MJCF of the rest of the model (physics options, the drones, their pads
and sensors: ``MjSpec.to_xml`` of the model without its world, a fraction of a
millisecond). Each flight gets its own copy of the cached model (``mj_copyModel``:
~60 ms for 3,000 people, nothing shared): a flight may change its model (the
wind sets ``opt.wind``, a user's component may change more) without touching
the next one's.

The cache is bounded (``MAX_ENTRIES`` models, ``MAX_BYTES`` of model buffers,
least recently used out first); ``info()`` counts builds and reuses, ``clear()``
empties it. Worker processes (sweeps, xdist) each keep their own.
"""

from __future__ import annotations

import copy
import threading
from collections import OrderedDict
from collections.abc import Callable

from .._mujoco import mujoco
from ..physics import RHO_SEA_LEVEL
from .mjspec import world_spec

#: at most this many compiled models are kept
MAX_ENTRIES = 8
#: bytes: at most this much model buffer is kept (a 3,000-person urban world is ~100 MB)
MAX_BYTES = 256 * 2 ** 20

_LOCK = threading.Lock()
_MODELS: OrderedDict = OrderedDict()
_COUNTS = {"builds": 0, "reuses": 0}


def world_key(world) -> tuple:
    """The world's part of the key: its type and content (None: the empty ground)."""
    if world is None:
        return ("none",)
    fingerprint = getattr(world, "fingerprint", None)
    if fingerprint is None:                # not a World: no content to key on
        return ("object", id(world))
    return (type(world).__module__, type(world).__qualname__, fingerprint())


def compiled(name: str, world, add_drones: Callable[[mujoco.MjSpec], None], *,
             physics_dt: float, rho: float = RHO_SEA_LEVEL) -> mujoco.MjModel:
    """The model of ``world`` (``airframe.mjspec.world_spec``) with what ``add_drones(spec)``
    adds (the drones and their sensors): a copy of the cached one when this process
    built it before, else built, compiled and cached."""
    rest = world_spec(name, None, physics_dt=physics_dt, rho=rho)
    add_drones(rest)
    key = (world_key(world), rest.to_xml())
    cacheable = key[0][0] != "object"
    with _LOCK:
        model = _MODELS.get(key) if cacheable else None
        if model is not None:
            _MODELS.move_to_end(key)
            _COUNTS["reuses"] += 1
    if model is not None:
        return copy.copy(model)
    spec = world_spec(name, world, physics_dt=physics_dt, rho=rho)
    add_drones(spec)
    model = spec.compile()
    with _LOCK:
        _COUNTS["builds"] += 1
        if cacheable and model.nbuffer <= MAX_BYTES:
            _MODELS[key] = model
            _evict()
    return copy.copy(model) if cacheable else model


def _evict() -> None:
    """Drop the least recently used models beyond the bounds (under the lock)."""
    while len(_MODELS) > MAX_ENTRIES or sum(m.nbuffer for m in _MODELS.values()) > MAX_BYTES:
        _MODELS.popitem(last=False)


def info() -> dict:
    """``{"builds": n, "reuses": n, "models": n, "bytes": n}`` of this process's cache."""
    with _LOCK:
        return {**_COUNTS, "models": len(_MODELS),
                "bytes": sum(m.nbuffer for m in _MODELS.values())}


def clear() -> None:
    """Forget every cached model and reset the counts."""
    with _LOCK:
        _MODELS.clear()
        _COUNTS.update(builds=0, reuses=0)
