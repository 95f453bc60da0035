"""Fly a sweep's variants and gather them into one DataFrame.

The per-flight core (``Mission.run``) flies every variant, in this process
(``workers=1``) or across processes (a ``ProcessPoolExecutor`` with the
``spawn`` start method, safe under pytest, threads and macOS). The base
mission travels to each worker once (pickled, in the pool's initializer),
the variants as small dicts; results come back in the variants' order, so
the same seed gives the same DataFrame whatever the worker count or
executor. A variant that raises (a ``SimulationError``, a combination the
mission rejects, a bug in a probe) or kills its worker is a row with its
``error``, never a lost sweep; an interrupt returns the rows finished so far.
``executor=`` flies the variants elsewhere (any ``concurrent.futures.Executor``,
a Dask cluster): ``executors.py``. A progress bar (``progress.py``) counts the
drone-seconds done and to go.

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
import os
import time
import warnings
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from typing import Any

import pandas as pd

from .. import budgets as _budgets
from .. import cache as _cache
from ..errors import ConfigError, FlockAIError
from ..mission import Mission
from . import axes as _axes
from . import design
from . import executors as _executors
from . import progress as _progress
from . import worker as _worker
from .batched import params as _batched
from .sweep_result import SweepResult
from .worker import Outcome, row_of

BACKENDS = ("process", "mjx", "jax", "auto")
#: backend="auto" batches from this many variants: below it, compiling the batch (tens of
#: seconds on a CPU, once per machine with the compile cache) costs more than it saves
AUTO_MIN_VARIANTS = 16
#: JAX platforms the mjx backend runs on (None: JAX's default device)
DEVICES = (None, "cpu", "gpu", "cuda", "tpu")
#: variants per task on an executor with a batched backend (one compiled batch each)
BATCHED_BATCH = 4096


class SweepInterrupted(UserWarning):
    """A sweep was interrupted: it returns the rows finished so far."""


def default_workers() -> int:
    """Worker processes of a sweep by default: the CPUs this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:       # macOS, Windows
        return max(1, os.cpu_count() or 1)


def sweep(base_mission: Mission, *, samples: int | None = None, method: str = "grid",
          seed: int = 0, budgets: dict | None = None, workers: int | None = None,
          backend: str = "process", device: str | None = None, executor: Any = None,
          batch_size: int | None = None, progress: bool | None = None,
          **axes: Any) -> pd.DataFrame:
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

    ``executor``: where the variants fly instead of this machine's processes
    (any ``concurrent.futures.Executor``, a ``distributed.Client`` or a Dask
    scheduler address; see ``executors.py``; ``workers`` is then unused),
    ``batch_size`` variants per task (default: 1 with ``backend="process"``,
    else ``BATCHED_BATCH``). A variant
    that raises or kills its worker is a row with its ``error``; an interrupt
    (Ctrl-C) returns the rows finished so far, the others ``interrupted``
    (``df.attrs["interrupted"]``). ``progress``: a bar of drone-seconds done and
    to go (None: when stderr is a terminal; ``progress.py``).
    """
    if not isinstance(base_mission, Mission):
        raise ConfigError(f"sweep: base_mission = {base_mission!r} is not a fa.Mission")
    _check_backend(backend, base_mission, device)
    for name in axes:
        _axes.check_name(name)
    plan, to_check = design.variants(axes, method, samples, seed)
    for name, values in to_check.items():
        _axes.check_values(base_mission, name, values)
    if budgets is not None and not isinstance(budgets, dict):
        raise ConfigError(f"sweep: budgets = {budgets!r} is not allowed; expected a dict "
                          f"{{kpi: '<op> <number> [unit]'}}")
    parsed = _budgets.parse_many(budgets or {})
    workers = _check_workers(workers)
    _executors.check_executor(executor)
    _check_batch_size(batch_size)
    _progress.check(progress)
    ran, why = (backend_choice(base_mission, len(plan), device) if backend == "auto"
                else (backend, "asked"))
    wall0 = time.perf_counter()
    interrupted = False
    jax_cpu: dict = {"jax_cpu_threads": None, "jax_cpu_shards": None}  # a batch flown here
    if ran == "process" or executor is not None:
        outcomes, interrupted = fly(base_mission, plan, workers, executor=executor,
                                    backend=ran, device=device, batch_size=batch_size,
                                    progress=progress)
    else:                       # the batched path neither reads nor stores the flight cache
        rows, jax_cpu = _fly_batched_here(base_mission, plan, device, ran)
        outcomes = [Outcome(r, None, None) for r in rows]
    wall = time.perf_counter() - wall0
    df = frame([o.row for o in outcomes], list(axes), parsed)
    df.attrs.update({"axes": list(axes), "method": method, "samples": samples, "seed": seed,
                     "budgets": {b.kpi: b.text for b in parsed}, "workers": workers,
                     "wall_s": wall, "backend": ran, "backend_asked": backend,
                     "backend_why": why, "device": device,
                     **jax_cpu,
                     "executor": _executors.describe_executor(executor),
                     "interrupted": interrupted,
                     "tracebacks": {i: o.trace for i, o in enumerate(outcomes) if o.trace},
                     "cache": dict(Counter(o.status for o in outcomes if o.status is not None))})
    return SweepResult.of(df)


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
            raise ConfigError(f"sweep: device = {device!r} needs a batched backend, backend='jax' "
                              f"or backend='mjx'; "
                              f"backend='process' flies on this machine's CPU cores")
        return
    _batched.check(base, backend)
    why = _batched.free_flight_unsupported(base) if backend == "jax" else None
    if why is not None:
        raise ConfigError(f"sweep: backend='jax' cannot fly this drone ({why}); allowed: "
                          f"backend='mjx' (MJX's full physics) or 'process'")


def choose_backend(base, n_variants: int, device=None) -> str:
    """``backend="auto"``: "jax" (the free-flight batch) for a mission the batched path
    flies, with JAX installed, of at least ``AUTO_MIN_VARIANTS`` variants or with a
    ``device``; "mjx" there if the free-flight body cannot fly the drone; else "process"."""
    return backend_choice(base, n_variants, device)[0]


def backend_choice(base, n_variants: int, device=None) -> tuple[str, str]:
    """``choose_backend``'s backend and why (``df.attrs["backend_why"]``): a batched
    backend never flies a mission it would change (a policy, a task: its refusal is the
    reason given for "process")."""
    if device is None and n_variants < AUTO_MIN_VARIANTS:
        return "process", f"{n_variants} variants, fewer than {AUTO_MIN_VARIANTS} to batch"
    try:   # what the mission asks decides first: installing JAX would not change it
        _batched.check(base)
    except ConfigError as exc:
        return "process", str(exc)
    if importlib.util.find_spec("jax") is None or importlib.util.find_spec("mujoco.mjx") is None:
        return "process", "JAX or MJX is not installed"
    why = _batched.free_flight_unsupported(base)
    if why is None:
        return "jax", f"{n_variants} variants the free-flight batch flies"
    return "mjx", f"the free-flight body cannot fly this drone ({why})"


def _fly_batched(base, plan, device, physics="mjx") -> list[dict]:
    """The variants' rows from one JAX batch (what a worker runs)."""
    return _fly_batched_here(base, plan, device, physics)[0]


def _fly_batched_here(base, plan, device, physics="mjx") -> tuple[list[dict], dict]:
    """The variants in one JAX batch (the backend's modules import JAX: loaded here), and
    the XLA CPU threads and shards it ran on (``batched/cpu_threads.py``, ``shards.py``);
    ``physics``: the batched backend ("jax": the free-flight body, "mjx")."""
    try:
        from .batched import engine
    except ImportError as exc:
        raise ConfigError(f"sweep: backend={physics!r} needs JAX and MJX ({exc}); install them "
                          f"with pip install 'pytest-flockai[mjx]', or use backend='process'") from None
    rows = engine.fly(base, plan, device, physics)
    return rows, {k: engine.LAST_TIMINGS[k] for k in ("jax_cpu_threads", "jax_cpu_shards")}


def _check_batch_size(batch_size) -> None:
    if batch_size is not None and (isinstance(batch_size, bool) or not isinstance(batch_size, int)
                                   or batch_size < 1):
        raise ConfigError(f"sweep: batch_size = {batch_size!r} is not allowed; expected None "
                          f"(1 variant per task, or {BATCHED_BATCH} with a batched backend) or "
                          f"an integer >= 1")


def _check_workers(workers) -> int:
    if workers is None:
        return default_workers()
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ConfigError(f"sweep: workers = {workers!r} is not allowed; expected None (every "
                          f"available core) or an integer >= 1")
    return workers


def fly(base, plan: list[dict], workers: int, *, executor=None, backend="process", device=None,
        batch_size=None, progress=None) -> tuple[list[Outcome], bool]:
    """One ``Outcome`` per variant, in the plan's order, and whether the sweep was
    interrupted (the variants not flown then are rows ``interrupted``)."""
    cache = _cache.active() if backend == "process" else None
    done = {i: hit for i, v in enumerate(plan) if (hit := _cached(base, v, cache)) is not None}
    todo = [i for i in range(len(plan)) if i not in done]
    base_until = base.until
    bar = _progress.Progress({i: _progress.expected_s(base_until, plan[i]) for i in todo},
                             _progress.wanted(progress), done=len(done),
                             delay_s=0.0 if progress else _progress.DELAY_S)

    def sink(i: int, outcome: Outcome) -> None:
        done[i] = outcome
        bar.update(i, outcome.row.get("sim_time_s"))

    interrupted = False
    try:
        _dispatch(base, plan, todo, sink, workers, executor, backend, device, batch_size, cache)
    except KeyboardInterrupt:
        interrupted = True
    finally:
        bar.close()
    rows = [done.get(i) or _worker.failed(plan[i], "interrupted", "interrupted")
            for i in range(len(plan))]
    if interrupted:
        warnings.warn(f"sweep interrupted: {len(done)} of {len(plan)} variants have rows; the "
                      f"others are rows with error 'interrupted'", SweepInterrupted, stacklevel=3)
    return rows, interrupted


def _dispatch(base, plan, todo, sink, workers, executor, backend, device, batch_size,
              cache) -> None:
    if not todo:
        return
    if executor is None and backend == "process" and min(workers, len(todo)) <= 1:
        _executors.fly_here(base, plan, todo, sink)
        return
    where: tuple | None = (str(cache.directory), cache.mode) if cache is not None else None
    if where is not None and executor is None:      # this machine: the caller's own key
        where += (cache.key,)
    job = _worker.make_job(base, where, backend, device,
                           _fly_batched if backend != "process" else None)
    if executor is None:
        _executors.fly_own(job, plan, todo, sink, min(workers, len(todo)), _spawn_pool)
        return
    size = batch_size or (1 if backend == "process" else BATCHED_BATCH)
    with _executors.opened(executor) as (ex, client):
        _executors.fly_on(ex, job, plan, todo, sink, size, client)


def _spawn_pool(size: int, ctx, initargs: tuple) -> ProcessPoolExecutor:
    """A pool of ``size`` spawned processes, each loading the base once."""
    return ProcessPoolExecutor(size, mp_context=ctx, initializer=_worker.install,
                               initargs=initargs)


def _cached(base, values: dict, cache) -> Outcome | None:
    """The variant's outcome ("hit") when the cache holds its flight, else None."""
    if cache is None or not cache.reads:
        return None
    try:
        mission = _axes.apply(base, values)
    except FlockAIError:
        return None                  # flown (and reported) as a failed variant
    found = cache.lookup(mission)
    if found.result is None:
        return None
    return Outcome(row_of(values, found.result, None), "hit", None)


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
