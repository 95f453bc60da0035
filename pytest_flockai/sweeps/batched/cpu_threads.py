"""How many threads JAX's CPU client runs the batch on.

A batched tick is hundreds of short XLA kernels over arrays of a few thousand
numbers. XLA's CPU client splits each kernel over a thread pool as wide as the
CPUs the process may use when the client starts, and for kernels this short the
hand-over costs about what the split gains: on the 2-core CI machine one thread runs
the 1,024-variant batch of ``benchmarks/peers.py`` 20-25 % faster in wall time, on
half the CPU time (``docs/explanation/batched-backend.md``), and leaves the other
core to the rest of the test run (an xdist worker, the flight cache).

XLA sizes its pool from the CPU affinity at the moment the client is created, once
per process. So when the batched backend is the first to start JAX, it starts it
with the process's affinity narrowed to one CPU and restores the affinity of every
thread at once (the client's own threads included, so batches in two processes use two
cores); nothing else in the process is touched. ``$FLOCKAI_JAX_CPU_THREADS`` chooses: ``1``
(the default) or ``all`` (XLA's own pool). When JAX was started before (a user's own
JAX code, an earlier ``jax.devices()``), its client is left as it is and ``mode()``
says so; results are the same either way (the batch has no reduction across
variants that a thread split could reorder: ``tests/sweeps/test_sweep_batched.py``).
"""

from __future__ import annotations

import os

import jax

from ...errors import ConfigError
from . import shards

try:                                        # JAX's own query, not in its public API
    from jax._src import xla_bridge as _xla_bridge
except ImportError:                         # pragma: no cover - another JAX layout
    _xla_bridge = None                      # type: ignore[assignment]

ENV = "FLOCKAI_JAX_CPU_THREADS"
CHOICES = ("1", "all")
_STATE: dict = {"mode": None}


def wanted() -> str:
    """``$FLOCKAI_JAX_CPU_THREADS``: "1" (default) or "all"; a ConfigError otherwise."""
    value = os.environ.get(ENV, "1").strip().lower() or "1"
    if value not in CHOICES:
        raise ConfigError(f"${ENV} = {value!r} is not allowed; allowed: 1 (one XLA thread, "
                          f"the default) or all (XLA's pool over every CPU)")
    return value


def _initialized() -> bool:
    query = getattr(_xla_bridge, "backends_are_initialized", None)
    if query is None:                       # unknown: assume started, leave it alone
        return True
    return bool(query())


def _restore(cpus: set[int]) -> None:
    """Every thread of the process back on ``cpus``: the threads the client started while
    the affinity was narrowed inherited it (they would all share the first CPU, and two
    processes' batches would share one core), the pool's size stays one."""
    try:
        threads = [int(t) for t in os.listdir("/proc/self/task")]
    except OSError:                         # no /proc: only this thread is known
        threads = [0]
    for tid in threads:
        try:
            os.sched_setaffinity(tid, cpus)
        except OSError:                     # a thread that ended meanwhile
            pass
    os.sched_setaffinity(0, cpus)


def start(device: str | None) -> str:
    """Start JAX's backends (once per process) with the thread count asked for, for a
    batch on ``device``; returns what runs: "1 thread", "all CPUs" or
    "as started before"."""
    if _STATE["mode"] is not None:
        return _STATE["mode"]
    want = wanted()
    flags = os.environ.get("XLA_FLAGS")
    try:
        mode = _start(want, device)
    finally:                                # the host devices were for this client only
        if flags is None:
            os.environ.pop("XLA_FLAGS", None)
        else:
            os.environ["XLA_FLAGS"] = flags
    _STATE["mode"] = mode
    return mode


def _start(want: str, device: str | None) -> str:
    if _initialized():
        return "as started before"
    shards.prepare(device)                  # the host devices the shards run on
    if want == "all" or device not in (None, "cpu") or not hasattr(os, "sched_setaffinity"):
        jax.devices()
        return "all CPUs"
    cpus = os.sched_getaffinity(0)
    try:
        os.sched_setaffinity(0, {min(cpus)})
        jax.devices()
    finally:
        _restore(cpus)
    return "1 thread"
