"""What a sweep runs where its variants fly: in this process, in a spawned pool
worker, or on a cluster worker (any ``concurrent.futures.Executor``).

A ``Job`` is everything a worker needs besides the variants: the base mission
pickled (``blob``; None when a pool's initializer installed it in the worker),
the caller's flight cache (directory and mode), the backend and device, and
the names the base refers to in ``__main__``. ``run_batch(job, batch)`` flies
a batch of ``(index, values)`` pairs and returns one ``Outcome`` per variant:
its row, its cache status and, for an exception that is not one pytest-flockai
raises on purpose, the traceback's text. Any exception of a variant becomes
that variant's row (``error``: the type and the message); nothing a variant
raises ends the sweep.

A worker checks first that it can load the base: when it cannot (a pilot,
probe or component class defined in a script or notebook's ``__main__``,
which other processes cannot import), the batch answers with the reason
(``Unloadable``) instead of dying, and the caller raises a ``ConfigError``
naming what to move out of ``__main__``.
"""

from __future__ import annotations

import hashlib
import io
import math
import os
import pickle
import traceback
from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

from .. import cache as _cache
from ..errors import ConfigError, FlockAIError
from ..recording import recording
from . import axes as _axes

#: how many bases a worker process keeps loaded (a cluster worker serves several sweeps)
KEEP_BASES = 4
_BASES: dict = {}         # digest -> the base mission, or the text of why it cannot be loaded
_CACHES: dict = {}        # (directory, mode) -> FlightCache, inside a worker process
_STARTED: list = []       # a pool's shared array: pid of the worker flying variant i, else 0


class Outcome(NamedTuple):
    """One variant's answer: its row, its flight cache status, a traceback or None."""
    row: dict
    status: str | None
    trace: str | None


@dataclass(frozen=True)
class Unloadable:
    """A worker could not load the base mission: ``text`` says why and what to do."""
    text: str


@dataclass(frozen=True)
class Job:
    """A sweep's base mission and settings, as they travel to the workers."""
    digest: str
    blob: bytes | None
    where: tuple | None
    backend: str = "process"
    device: str | None = None
    main_names: tuple = ()
    fly_batched: Callable | None = None

    def without_blob(self) -> Job:
        return Job(self.digest, None, self.where, self.backend, self.device, self.main_names,
                   self.fly_batched)


class _MainFinder(pickle.Pickler):
    """A pickler that notes the classes and functions it saves from ``__main__``."""

    def __init__(self, file):
        super().__init__(file, protocol=pickle.HIGHEST_PROTOCOL)
        self.main_names: set = set()

    def reducer_override(self, obj):
        if (isinstance(obj, type) or callable(obj)) \
                and getattr(obj, "__module__", None) in ("__main__", "__mp_main__"):
            self.main_names.add(getattr(obj, "__qualname__", repr(obj)))
        return NotImplemented


def pickled(base) -> tuple[bytes, tuple]:
    """The base mission pickled for other processes (its live subscribers stay
    here: ``Mission.__getstate__`` leaves them out) and the names it refers to in
    ``__main__``; ConfigError if it cannot be pickled."""
    buf = io.BytesIO()
    finder = _MainFinder(buf)
    try:
        finder.dump(base)
    except (pickle.PicklingError, TypeError, AttributeError) as exc:
        raise ConfigError(f"sweep: workers > 1 (and executors) send the base mission to other "
                          f"processes, but "
                          f"it cannot be pickled ({type(exc).__name__}: {exc}); define your "
                          f"components, probes and pilots at module level, or use "
                          f"workers=1") from None
    return buf.getvalue(), tuple(sorted(finder.main_names))


def make_job(base, where, backend="process", device=None, fly_batched=None) -> Job:
    """The ``Job`` of a sweep of ``base`` (pickled once here)."""
    blob, names = pickled(base)
    return Job(hashlib.sha256(blob).hexdigest(), blob, where, backend, device, names,
               fly_batched)


def install(blob: bytes, digest: str, main_names: tuple, started=None) -> None:
    """A pool's initializer: load the base once per worker process (or note why not)."""
    _STARTED[:] = [started] if started is not None else []
    _load(blob, digest, main_names)


def _load(blob: bytes, digest: str, main_names: tuple):
    if digest not in _BASES:
        while len(_BASES) >= KEEP_BASES:
            _BASES.pop(next(iter(_BASES)))
        try:
            _BASES[digest] = pickle.loads(blob)
        except Exception as exc:        # noqa: BLE001 - any failure is reported, not raised
            _BASES[digest] = Unloadable(unloadable_text(exc, main_names))
    return _BASES[digest]


def unloadable_text(exc: BaseException, main_names: tuple) -> str:
    """Why a worker cannot load the base, and what to move where."""
    text = f"sweep: a worker process cannot load the base mission ({type(exc).__name__}: {exc})"
    if main_names:
        return (text + f"; {', '.join(main_names)} defined in __main__ (your script or "
                f"notebook) cannot be imported by other processes: move "
                f"{'it' if len(main_names) == 1 else 'them'} into a module (a .py file the "
                f"workers can import, e.g. myprobes.py beside your script), or use workers=1")
    return (text + "; install the same packages and your code's modules where the workers "
            "run, or use workers=1")


def run_batch(job: Job, batch: list, blob: bytes | None = None) -> list | Unloadable:
    """Fly ``batch`` (pairs ``(index, values)``) in this process: ``[(index, Outcome)]``.
    The base comes with the job, as ``blob`` (a Dask scatter), or from the pool's
    initializer."""
    blob = job.blob if blob is None else blob
    base = _BASES.get(job.digest) if blob is None else _load(blob, job.digest, job.main_names)
    if base is None:
        return Unloadable(f"sweep: a worker process lost the base mission {job.digest[:12]}")
    if isinstance(base, Unloadable):
        return base
    cache = _open_cache(job.where)
    with _cache.caching(cache), recording(_drop):
        if job.backend != "process":
            return _batched(job, base, batch)
        return [(i, _marked(i, base, values)) for i, values in batch]


def _open_cache(where):
    """The caller's flight cache in this worker: ``(directory, mode)``, and the caller's
    key for the sweep's own pool (a cluster's workers use their own default key)."""
    if where is None:
        return None
    directory, mode, *key = where
    if (directory, mode) not in _CACHES:
        _CACHES[(directory, mode)] = _cache.FlightCache(directory, mode,
                                                        key=key[0] if key else None)
    return _CACHES[(directory, mode)]


def _marked(i: int, base, values: dict) -> Outcome:
    """One variant, marked as started in the pool's shared array while it flies."""
    started = _STARTED[0] if _STARTED else None
    if started is not None:
        started[i] = os.getpid()
    outcome = fly_one(base, values)
    if started is not None:
        started[i] = -1
    return outcome


def _batched(job: Job, base, batch: list) -> list:
    """A batch through the batched backend; a failure of the batch is every row's error."""
    plan = [values for _, values in batch]
    try:
        if job.fly_batched is None:
            raise ConfigError(f"sweep: backend = {job.backend!r} came without its batched path")
        rows = job.fly_batched(base, plan, job.device, job.backend)
    except Exception as exc:            # noqa: BLE001 - the batch's rows carry it
        error, trace = describe(exc)
        return [(i, Outcome(row_of(values, None, error), None, trace)) for i, values in batch]
    return [(i, Outcome(row, None, None)) for (i, _), row in zip(batch, rows)]


def _drop(result, mission) -> None:
    """The sink of a sweep's own flights: they are summed up in the DataFrame."""


def fly_one(base, values: dict) -> Outcome:
    """One variant of ``base``: every exception becomes the row's ``error``."""
    result, trace = None, None
    try:
        result = _axes.apply(base, values).run()
        error = None
    except FlockAIError as exc:
        result = getattr(exc, "result", None)
        error = f"{type(exc).__name__}: {exc}"
    except (Exception, SystemExit) as exc:  # noqa: BLE001 - a bug in user code: that row's error
        error, trace = describe(exc)
    status = (getattr(result, "cache", None) or {}).get("status")
    return Outcome(row_of(values, result, error), status, trace)


def describe(exc: BaseException) -> tuple[str, str]:
    """(``"Type: message"``, the traceback's text) of an exception."""
    return (f"{type(exc).__name__}: {exc}",
            "".join(traceback.format_exception(type(exc), exc, exc.__traceback__)))


def row_of(values: dict, result, error) -> dict:
    """A variant's row: its axis values, end reason, error, simulated time and KPIs."""
    row = dict(values)
    row["end_reason"] = getattr(result, "end_reason", None) or ("error" if error else None)
    row["error"] = error
    row["sim_time_s"] = result.sim_time_s if result is not None else math.nan
    if result is not None:
        row.update({k: float(v) for k, v in result.kpis.items()})
    return row


def failed(values: dict, error: str, end_reason: str = "error") -> Outcome:
    """The outcome of a variant that did not fly to its end (worker died, interrupted)."""
    row = row_of(values, None, error)
    row["end_reason"] = end_reason
    return Outcome(row, None, None)
