"""The flight's watchdog: ``Mission(max_wall_s=...)`` holds even inside a call that never
returns (a policy's ``decide``, a component's ``step``, a model).

``WallClockGuard`` (``ending.py``) looks at the host clock between ticks; a call that
never returns never gets back to it. The watchdog interrupts the flight's thread at
the same deadline, wherever it is, with ``Overrun`` (a ``BaseException``, so that a
user's ``except Exception`` does not swallow it); ``loop.fly`` turns it into the
``SimulationError`` of ``max_wall_s`` (``end_reason`` ``"wall_time"``, the partial
result attached by ``Mission.run``), naming the call that was running.

The mechanism:

- in the main thread (pytest, a sweep's worker process), a ``SIGALRM`` timer
  (``signal.setitimer``): its handler raises ``Overrun`` at the next Python bytecode,
  and a blocking system call (``time.sleep``, a read) is interrupted too;
- in any other thread (a Dask or thread-pool worker), or when ``SIGALRM`` is already
  in use (pytest-timeout's signal method, another timer), a watchdog thread that
  sets ``Overrun`` as the flight thread's asynchronous exception
  (``PyThreadState_SetAsyncExc``), again every 0.5 s until it lands. It lands at
  the next Python bytecode: a C call that never returns to Python (a model stuck in
  native code, ``time.sleep`` in a worker thread) is interrupted only when it does.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import signal
import sys
import threading
import time
from collections.abc import Iterator

#: s between two tries of the watchdog thread while the flight thread has not stopped
RETRY_S = 0.5


class Overrun(BaseException):
    """Raised in the flight's thread when its ``max_wall_s`` deadline passed."""

    where = "the flight loop"


def _where(frame) -> str:
    """The innermost call outside this package's loop, e.g. ``decide (policies.py:12)``."""
    inner = None
    f = frame
    while f is not None:
        if inner is None and os.path.basename(f.f_code.co_filename) != "watchdog.py":
            inner = f
        f = f.f_back
    if inner is None:
        return "the flight loop"
    return (f"{inner.f_code.co_name} ({os.path.basename(inner.f_code.co_filename)}:"
            f"{inner.f_lineno})")


def _signal_free() -> bool:
    if threading.current_thread() is not threading.main_thread() or not hasattr(signal, "setitimer"):
        return False
    try:
        return (signal.getsignal(signal.SIGALRM) in (signal.SIG_DFL, None)
                and signal.getitimer(signal.ITIMER_REAL) == (0.0, 0.0))
    except (ValueError, OSError):
        return False


@contextlib.contextmanager
def watching(deadline: float | None) -> Iterator[None]:
    """Interrupt this thread with ``Overrun`` once ``time.perf_counter()`` passes
    ``deadline`` (None: no watchdog) until the block ends."""
    if deadline is None:
        yield
        return
    if _signal_free():
        with _by_signal(deadline):
            yield
    else:
        with _by_thread(deadline):
            yield


@contextlib.contextmanager
def _by_signal(deadline: float) -> Iterator[None]:
    armed = [True]

    def fire(signum, frame):
        if armed[0]:
            armed[0] = False
            exc = Overrun()
            exc.where = _where(frame)
            raise exc

    old = signal.signal(signal.SIGALRM, fire)
    signal.setitimer(signal.ITIMER_REAL, max(deadline - time.perf_counter(), 1e-3))
    try:
        yield
    finally:
        armed[0] = False
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, old)


@contextlib.contextmanager
def _by_thread(deadline: float) -> Iterator[None]:
    tid = threading.get_ident()
    done = threading.Event()
    lock = threading.Lock()
    fired = [False]

    def watch():
        wait = max(deadline - time.perf_counter(), 0.0)
        while not done.wait(wait):
            with lock:
                if done.is_set():
                    return
                frame = sys._current_frames().get(tid)
                Overrun.where = _where(frame) if frame is not None else "the flight loop"
                ctypes.pythonapi.PyThreadState_SetAsyncExc(ctypes.c_ulong(tid),
                                                           ctypes.py_object(Overrun))
                fired[0] = True
            wait = RETRY_S

    t = threading.Thread(target=watch, name="flockai-watchdog", daemon=True)
    t.start()
    try:
        yield
    finally:
        with lock:
            done.set()
        t.join()
        if fired[0]:
            _settle(tid)


class _Settled(BaseException):
    """Replaces an ``Overrun`` that may still be pending, and lands at once, here."""


def _settle(tid: int) -> None:
    """Make sure no asynchronous exception is left pending on this thread.

    ``PyThreadState_SetAsyncExc(tid, NULL)`` would drop a pending one but leaves the
    interpreter's "async exception" flag raised (CPython only lowers it when an exception
    actually lands), and with that flag stuck a traced frame (``sys.settrace`` with opcode
    events: hypothesis' explain phase, coverage tools) could spin for ever. So a harmless
    exception replaces whatever is pending and is caught on the next backward jump."""
    try:      # it may land right after the call (CPython checks after calls) or in the loop
        ctypes.pythonapi.PyThreadState_SetAsyncExc(ctypes.c_ulong(tid),
                                                   ctypes.py_object(_Settled))
        for _ in range(1_000_000):
            pass
    except _Settled:
        pass


__all__ = ["Overrun", "RETRY_S", "watching"]
