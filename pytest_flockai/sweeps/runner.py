"""Fly a sweep's variants and gather them into one DataFrame.

The per-flight core (``Mission.run``) flies every variant, in this process
(``workers=1``) or across processes (a ``ProcessPoolExecutor`` with the
``spawn`` start method, safe under pytest, threads and macOS). The base
mission travels to each worker once (pickled, in the pool's initializer),
the variants as small dicts; results come back in the variants' order, so
the same seed gives the same DataFrame whatever the worker count. A
variant that ends in a ``SimulationError`` (or a combination the mission
rejects) is a row with its ``error``, not a lost sweep.

``backend="jax"`` flies every variant in one batch instead (the core's
components in JAX and a free-flying rigid body with the ground handled apart,
``batched/``; ``pip install 'pytest-flockai[mjx]'``), ``backend="mjx"`` the same
batch on MJX's full physics: same columns, for Hover, Waypoints and ZigZag
missions without tasks (``batched.params.check`` names anything else).
``backend="auto"`` picks the batch ("jax", or "mjx" where the free-flight body
cannot fly the drone) for a batchable mission of at least ``AUTO_MIN_VARIANTS``
variants or with a ``device``, else the process pool; ``df.attrs["backend"]``
says which ran (``"backend_asked"``: what was asked).

Flights of a sweep are not handed to the recording sink of the caller (the
pytest plugin records the sweep as a whole). Each variant is a flight of the
flight cache open in the caller's context (``pytest_flockai.cache``): the
caller looks every variant up first and sends only the misses to the workers,
which open the same cache directory in the same mode and store what they fly;
a sweep whose variants are all cached starts no worker. ``df.attrs["cache"]``
counts the variants per cache status ("hit", "stored", ...).
"""

from __future__ import annotations

import importlib.util
import math
import multiprocessing
import os
import pickle
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor

import pandas as pd

from .. import budgets as _budgets
from .. import cache as _cache
from ..errors import ConfigError, FlockAIError
from ..mission import Mission
from ..recording import recording
from . import axes as _axes
from . import design
from .batched import params as _batched

BACKENDS = ("process", "mjx", "jax", "auto")
#: backend="auto" batches from this many variants: below it, compiling the batch (tens of
#: seconds on a CPU, once per machine with the compile cache) costs more than it saves
AUTO_MIN_VARIANTS = 16
#: JAX platforms the mjx backend runs on (None: JAX's default device)
DEVICES = (None, "cpu", "gpu", "cuda", "tpu")
_BASE: list = []        # the base mission inside a worker process
_CACHE: list = []       # the caller's flight cache, opened again inside a worker process


def default_workers() -> int:
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:       # macOS, Windows
        return max(1, os.cpu_count() or 1)


def sweep(base_mission, *, samples=None, method="grid", seed=0, budgets=None, workers=None,
          backend="process", device=None, **axes) -> pd.DataFrame:
    """Fly ``base_mission`` once per variant of ``axes``; one DataFrame row per variant.

    Columns: the axes, ``end_reason``, ``error`` (None, or the failure of that
    variant), ``sim_time_s`` and every KPI of the flight; with ``budgets``
    (``{kpi: "<op> <number> [unit]"}``, as ``@pytest.mark.kpi``) one boolean
    column ``ok_<kpi>`` per budget and ``ok`` (every budget holds and the
    variant flew without error). ``df.attrs`` holds the sweep's settings and its
    wall time. ``backend="jax"`` / ``"mjx"`` fly the variants in one JAX batch
    (``device``: "cpu", "gpu", or None for JAX's default); ``workers`` is then unused.
    ``backend="auto"`` chooses (``choose_backend``); ``df.attrs["backend"]`` is the one
    that ran.
    """
    if not isinstance(base_mission, Mission):
        raise ConfigError(f"sweep: base_mission = {base_mission!r} is not a fa.Mission")
    _check_backend(backend, base_mission, device)
    for name in axes:
        _axes.check_name(name)
    plan, to_check = design.variants(axes, method, samples, seed)
    for name, values in to_check.items():
        for v in {repr(v): v for v in values}.values():
            _axes.check_value(base_mission, name, v)
    if budgets is not None and not isinstance(budgets, dict):
        raise ConfigError(f"sweep: budgets = {budgets!r} is not allowed; expected a dict "
                          f"{{kpi: '<op> <number> [unit]'}}")
    parsed = _budgets.parse_many(budgets or {})
    workers = _check_workers(workers)
    ran = choose_backend(base_mission, len(plan), device) if backend == "auto" else backend
    wall0 = time.perf_counter()
    if ran == "process":
        rows, statuses = fly(base_mission, plan, workers)
    else:                       # the batched path neither reads nor stores the flight cache
        rows, statuses = _fly_batched(base_mission, plan, device, ran), []
    wall = time.perf_counter() - wall0
    df = frame(rows, list(axes), parsed)
    df.attrs.update({"axes": list(axes), "method": method, "samples": samples, "seed": seed,
                     "budgets": {b.kpi: b.text for b in parsed}, "workers": workers,
                     "wall_s": wall, "backend": ran, "backend_asked": backend, "device": device,
                     "cache": dict(Counter(s for s in statuses if s is not None))})
    return df


def _check_backend(backend, base, device) -> None:
    if backend not in BACKENDS:
        raise ConfigError(f"sweep: backend = {backend!r} is not allowed; allowed: "
                          f"{', '.join(map(repr, BACKENDS))}")
    if device not in DEVICES:
        raise ConfigError(f"sweep: device = {device!r} is not allowed; allowed: "
                          f"{', '.join(map(repr, DEVICES))} (batched backends only)")
    if backend == "auto":
        return
    if backend == "process":
        if device is not None:
            raise ConfigError(f"sweep: device = {device!r} needs backend='mjx'; "
                              f"backend='process' flies on this machine's CPU cores")
        return
    _batched.check(base)


def choose_backend(base, n_variants: int, device=None) -> str:
    """``backend="auto"``: "jax" (the free-flight batch) for a mission the batched path
    flies, with JAX installed, of at least ``AUTO_MIN_VARIANTS`` variants or with a
    ``device``; "mjx" there if the free-flight body cannot fly the drone; else "process"."""
    if device is None and n_variants < AUTO_MIN_VARIANTS:
        return "process"
    if importlib.util.find_spec("jax") is None or importlib.util.find_spec("mujoco.mjx") is None:
        return "process"
    try:
        _batched.check(base)
    except ConfigError:
        return "process"
    return "jax" if _batched.free_flight_unsupported(base) is None else "mjx"


def _fly_batched(base, plan, device, physics) -> list[dict]:
    """The variants in one JAX batch (the backend's modules import JAX: loaded here)."""
    try:
        from .batched import engine
    except ImportError as exc:
        raise ConfigError(f"sweep: backend={physics!r} needs JAX and MJX ({exc}); install them "
                          f"with pip install 'pytest-flockai[mjx]', or use backend='process'") from None
    return engine.fly(base, plan, device, physics)


def _check_workers(workers) -> int:
    if workers is None:
        return default_workers()
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ConfigError(f"sweep: workers = {workers!r} is not allowed; expected None (every "
                          f"available core) or an integer >= 1")
    return workers


def fly(base, plan: list[dict], workers: int) -> tuple[list[dict], list]:
    """One row dict per variant, in the plan's order, and each variant's cache status."""
    cache = _cache.active()
    done = {i: hit for i, v in enumerate(plan) if (hit := _cached(base, v, cache)) is not None}
    todo = [i for i in range(len(plan)) if i not in done]
    workers = min(workers, len(todo))
    if workers <= 1:
        with recording(_drop):
            flown = [_fly_and_status(base, plan[i]) for i in todo]
    else:
        ctx = multiprocessing.get_context("spawn")
        where = (str(cache.directory), cache.mode) if cache is not None else None
        with ProcessPoolExecutor(workers, mp_context=ctx, initializer=_init,
                                 initargs=(_blob(base), where)) as pool:
            flown = list(pool.map(_fly_in_worker, [plan[i] for i in todo], chunksize=1))
    done.update(zip(todo, flown))
    return [done[i][0] for i in range(len(plan))], [done[i][1] for i in range(len(plan))]


def _cached(base, values: dict, cache) -> tuple[dict, str] | None:
    """(row, "hit") when the cache holds this variant's flight, else None."""
    if cache is None or not cache.reads:
        return None
    try:
        mission = _axes.apply(base, values)
    except FlockAIError:
        return None                  # flown (and reported) as a failed variant
    found = cache.lookup(mission)
    if found.result is None:
        return None
    return row_of(values, found.result, None), "hit"


def _blob(base) -> bytes:
    """The base mission pickled for the workers (its live subscribers stay here)."""
    subscribers, base.subscribers = base.subscribers, []
    try:
        return pickle.dumps(base)
    except (pickle.PicklingError, TypeError, AttributeError) as exc:
        raise ConfigError(f"sweep: workers > 1 send the base mission to other processes, but "
                          f"it cannot be pickled ({type(exc).__name__}: {exc}); define your "
                          f"components, probes and pilots at module level, or use "
                          f"workers=1") from None
    finally:
        base.subscribers = subscribers


def _drop(result, mission) -> None:
    """The sink of a sweep's own flights: they are summed up in the DataFrame."""


def _init(blob: bytes, where) -> None:
    _BASE[:] = [pickle.loads(blob)]
    _CACHE[:] = [_cache.FlightCache(*where) if where is not None else None]


def _fly_in_worker(values: dict) -> tuple[dict, str | None]:
    with _cache.caching(_CACHE[0]):
        return _fly_and_status(_BASE[0], values)


def _fly_and_status(base, values: dict) -> tuple[dict, str | None]:
    row, result = _fly(base, values)
    return row, (getattr(result, "cache", None) or {}).get("status")


def _fly(base, values: dict):
    try:
        result = _axes.apply(base, values).run()
        error = None
    except FlockAIError as exc:
        result = getattr(exc, "result", None)
        error = f"{type(exc).__name__}: {exc}"
    return row_of(values, result, error), result


def row_of(values: dict, result, error) -> dict:
    row = dict(values)
    row["end_reason"] = getattr(result, "end_reason", None) or ("error" if error else None)
    row["error"] = error
    row["sim_time_s"] = result.sim_time_s if result is not None else math.nan
    if result is not None:
        row.update({k: float(v) for k, v in result.kpis.items()})
    return row


def frame(rows: list[dict], axis_names: list, parsed: list) -> pd.DataFrame:
    df = pd.DataFrame(rows)
    for name in axis_names + ["end_reason", "error", "sim_time_s"]:
        if name not in df:
            df[name] = None
    df["error"] = pd.Series([r.get("error") for r in rows], index=df.index, dtype=object)
    if parsed:
        ok = pd.Series(True, index=df.index)
        for b in parsed:
            col = df[b.kpi] if b.kpi in df else pd.Series(math.nan, index=df.index)
            passed = [b.evaluate(None if _missing(v) else v)[0] for v in col]
            df[f"ok_{b.kpi}"] = passed
            ok &= pd.Series(passed, index=df.index)
        df["ok"] = ok & df["error"].isna()
    return df


def _missing(v) -> bool:
    return v is None or (isinstance(v, float) and math.isnan(v))
