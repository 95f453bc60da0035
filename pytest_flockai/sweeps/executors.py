"""Where a sweep's variants fly, and how finished work survives what goes wrong.

- ``workers=1`` (no executor): in this process, one after the other.
- ``workers=N`` (no executor): the sweep's own pools of ``N`` spawned processes
  (``concurrent.futures.ProcessPoolExecutor``), one variant per task. The base
  mission goes to each worker once (the pool's initializer). When a worker
  dies (a crash in native code, ``os._exit``, the OOM killer), the pool breaks:
  every row already finished is kept; the variant the dead worker was flying
  (each worker marks its variant in a shared array) becomes a row
  ``"worker died: exit 9"`` (or ``"... signal 9 (SIGKILL)"``), and the
  unfinished variants go to a fresh pool. When the dead worker cannot be told
  apart, the suspects fly alone, one pool of one process each.
- ``executor=``: any ``concurrent.futures.Executor`` (a process or thread pool
  of yours, ``distributed.Client(...).get_executor()``), a Dask
  ``distributed.Client``, or a scheduler address (``"tcp://host:8786"``: a
  client is opened for the sweep and closed after it). Variants go in batches
  of ``batch_size`` per task; results come back as each task finishes. On a Dask
  cluster (``on_dask.py``) a variant whose worker died under it flies again once,
  alone, then its row says ``"worker died: ..."`` naming the workers; when no
  worker is left the sweep waits a bounded time for one, then the variants not back
  are rows ``"not flown: no Dask worker left (...)"``. On another executor a task that
  fails without an answer has its variants flown again one per task once, then each
  is a row with the error. A pool of yours that breaks cannot be restarted by the
  sweep: every variant not back is a row ``"worker died: BrokenProcessPool: ..."``.

Every path returns the rows finished when it is interrupted (``KeyboardInterrupt``):
the caller marks the others ``interrupted``.
"""

from __future__ import annotations

import multiprocessing
import re
import signal
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, BrokenExecutor, CancelledError, Executor, wait
from contextlib import contextmanager

from ..errors import ConfigError
from ..recording import recording
from . import on_dask as _on_dask
from . import worker as _worker

#: s between checks of a sweep's futures (a wait is also where an interrupt lands)
WAIT_S = 0.5
#: how long a scheduler address may take to answer (s)
CONNECT_TIMEOUT_S = 30.0
_ADDRESS = re.compile(r"^([a-z][a-z0-9+.-]*://\S+|[^\s:/]+:\d{1,5})$")

Sink = Callable[[int, _worker.Outcome], None]


def check_address(address: str, where: str = "sweep: executor") -> str:
    """A Dask scheduler address such as ``tcp://127.0.0.1:8786`` or ``host:8786``."""
    if not isinstance(address, str) or not _ADDRESS.match(address.strip()):
        raise ConfigError(f"{where} = {address!r} is not allowed; expected a scheduler address "
                          f"such as 'tcp://127.0.0.1:8786' or 'scheduler-host:8786'")
    return address.strip()


def connect(address: str):
    """A ``distributed.Client`` connected to the scheduler at ``address``."""
    check_address(address)
    try:
        from distributed import Client
    except ImportError as exc:
        raise ConfigError(f"sweep: executor = {address!r} needs Dask's distributed ({exc}); "
                          f"install it with pip install 'pytest-flockai[dask]'") from None
    try:
        return Client(address, timeout=CONNECT_TIMEOUT_S)
    except (OSError, TimeoutError) as exc:
        raise ConfigError(f"sweep: executor = {address!r}: no Dask scheduler answered there "
                          f"({type(exc).__name__}: {exc}); start one with `dask scheduler` "
                          f"and workers with `dask worker {address}`") from None


def check_executor(executor) -> None:
    """ConfigError for an ``executor`` that is none of the kinds a sweep takes."""
    if executor is None or isinstance(executor, Executor):
        return
    if isinstance(executor, str):
        check_address(executor)
        return
    if not callable(getattr(executor, "get_executor", None)):
        raise ConfigError(f"sweep: executor = {executor!r} is not allowed; expected None (this "
                          f"machine's processes), a concurrent.futures.Executor, a "
                          f"distributed.Client or a Dask scheduler address")


def describe_executor(executor) -> str | None:
    """The executor as the sweep's ``attrs`` name it."""
    if executor is None or isinstance(executor, str):
        return executor
    return type(executor).__name__


@contextmanager
def opened(executor):
    """(the ``concurrent.futures.Executor`` behind ``executor`` for one sweep, its
    Dask client or None)."""
    if isinstance(executor, Executor):
        # distributed's ClientExecutor keeps its client as _client (no public name)
        yield executor, getattr(executor, "_client", None) if _is_dask(executor) else None
    elif isinstance(executor, str):
        client = connect(executor)
        try:
            yield client.get_executor(), client
        finally:
            client.close()
    else:
        yield executor.get_executor(), executor


def _is_dask(executor) -> bool:
    return type(executor).__module__.split(".")[0] == "distributed"


# -- the sweep's own pools ------------------------------------------------------------------------
def fly_own(job, plan: list, todo: list, sink: Sink, workers: int, pool_factory) -> None:
    """Fly ``todo`` on fresh spawned pools until every variant has a row."""
    queue, alone = list(todo), list[int]()
    while queue or alone:
        if alone:
            ids, size = [alone.pop(0)], 1
        else:
            ids, size, queue = queue, min(workers, len(queue)), []
        broken = _round(job, plan, ids, size, sink, pool_factory)
        if broken is None:
            continue
        unfinished, suspects, exits, progressed = broken
        died = {pid: code for pid, code in exits.items() if code not in (None, -signal.SIGTERM)}
        culprits = {i: died[pid] for i, pid in suspects.items() if pid in died}
        if not culprits and size == 1 and len(suspects) == 1:
            culprits = {i: exits.get(pid) for i, pid in suspects.items()}
        for i, code in culprits.items():
            sink(i, _worker.failed(plan[i], dead_text(code)))
        rest = [i for i in unfinished if i not in culprits]
        if not culprits and not suspects and not progressed:
            raise ConfigError(_startup_text(exits))
        if not culprits and suspects:
            alone += [i for i in rest if i in suspects]
            rest = [i for i in rest if i not in suspects]
        queue = rest + queue


def dead_text(code) -> str:
    """``"worker died: exit 9"``, ``"worker died: signal 9 (SIGKILL)"`` or ``"worker died"``."""
    if code is None:
        return "worker died"
    if code < 0:
        try:
            return f"worker died: signal {-code} ({signal.Signals(-code).name})"
        except ValueError:
            return f"worker died: signal {-code}"
    return f"worker died: exit {code}"


def _startup_text(exits: dict) -> str:
    codes = ", ".join(dead_text(c)[len("worker died: "):] for c in exits.values()
                      if c is not None) or "no exit status"
    return (f"sweep: the worker processes died before flying any variant ({codes}). In a "
            f"script, call fa.sweep under `if __name__ == \"__main__\":` (workers > 1 start new "
            f"Python processes that import your script), or use workers=1")


def _round(job, plan, ids, size, sink, pool_factory):
    """One pool over ``ids``: None when every variant came back, else (unfinished,
    {suspect: pid}, {pid: exit code}, whether any variant finished)."""
    ctx = multiprocessing.get_context("spawn")
    started = ctx.Array("q", len(plan), lock=False)
    pool = pool_factory(size, ctx, (job.blob, job.digest, job.main_names, started))
    light, finished, procs = job.without_blob(), set(), {}
    try:
        futures = {pool.submit(_worker.run_batch, light, [(i, plan[i])]): i for i in ids}
        pending = set(futures)
        while pending:
            done, pending = wait(pending, timeout=WAIT_S, return_when=FIRST_COMPLETED)
            for f in done:
                _take_own(f, futures[f], plan, sink, finished)
        procs = dict(getattr(pool, "_processes", None) or {})
    except BaseException:
        _terminate(pool)
        raise
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
    unfinished = [i for i in ids if i not in finished]
    if not unfinished:
        return None
    suspects = {i: started[i] for i in unfinished if started[i] > 0}
    exits = {p.pid: p.exitcode for p in procs.values()}
    return unfinished, suspects, exits, bool(finished)


def _take_own(f, i, plan, sink, finished) -> None:
    try:
        answer = f.result()
    except BrokenExecutor:
        return                           # sorted out after the round
    except Exception as exc:             # noqa: BLE001 - the answer could not come back
        answer = [(i, _worker.failed(plan[i], f"not flown: {_worker.describe(exc)[0]}"))]
    if isinstance(answer, _worker.Unloadable):
        raise ConfigError(answer.text)
    for j, outcome in answer:
        sink(j, outcome)
        finished.add(j)


def _terminate(pool) -> None:
    """Stop a pool's workers now (an interrupt must not wait for their flights)."""
    for p in list((getattr(pool, "_processes", None) or {}).values()):
        p.terminate()


# -- any executor -----------------------------------------------------------------------------------
def fly_on(executor: Executor, job, plan: list, todo: list, sink: Sink, batch_size: int,
           client=None) -> None:
    """Fly ``todo`` on ``executor`` in batches, each result taken as it finishes. With
    a Dask ``client`` the sweep is ``on_dask.fly``'s (the base scattered to the workers
    once, dying workers costing no innocent row)."""
    if client is not None:
        # distributed's ClientExecutor keeps its submit options as _kwargs (no public name)
        _on_dask.fly(client, job, plan, todo, sink, batch_size,
                     getattr(executor, "_kwargs", None))
        return
    pending: dict = {}

    def submit(ids: list, retried: bool) -> None:
        try:
            f = executor.submit(_worker.run_batch, job, [(i, plan[i]) for i in ids])
        except (BrokenExecutor, RuntimeError) as exc:    # broken, or shut down
            for i in ids:
                sink(i, _worker.failed(plan[i], f"not flown: {_worker.describe(exc)[0]}"))
            return
        pending[f] = (ids, retried)

    try:
        for k in range(0, len(todo), batch_size):
            submit(todo[k:k + batch_size], False)
        while pending:
            done, _ = wait(list(pending), timeout=WAIT_S, return_when=FIRST_COMPLETED)
            for f in done:
                ids, retried = pending.pop(f)
                _take(f, ids, retried, plan, sink, submit)
    except BaseException:
        for f in pending:
            f.cancel()
        raise


def _take(f, ids, retried, plan, sink, submit) -> None:
    try:
        answer = f.result()
    except Exception as exc:             # noqa: BLE001 - a task lost, not a variant's error
        # a task the executor cancelled was no variant's fault: flown again, alone,
        # even a batch of one
        lost = isinstance(exc, CancelledError)
        if (len(ids) > 1 or lost) and not retried and not isinstance(exc, BrokenExecutor):
            for i in ids:
                submit([i], True)
            return
        name = type(exc).__name__
        text = _worker.describe(exc)[0]
        if lost:
            text = "not flown: the executor cancelled its task twice"
        elif name in ("KilledWorker", "BrokenProcessPool"):
            text = f"worker died: {text}"
        else:
            text = f"not flown: {text}"
        for i in ids:
            sink(i, _worker.failed(plan[i], text))
        return
    if isinstance(answer, _worker.Unloadable):
        raise ConfigError(answer.text)
    for i, outcome in answer:
        sink(i, outcome)


def fly_here(base, plan: list, todo: list, sink: Sink) -> None:
    """Fly ``todo`` in this process, one after the other."""
    with recording(_worker._drop):
        for i in todo:
            sink(i, _worker.fly_one(base, plan[i]))
