"""Signals, so an interrupted run still leaves its reports.

- SIGTERM (a CI runner cancelling the job, ``timeout``, ``kill``) ends the run
  the way Ctrl-C does: pytest stops, marks the session interrupted and runs
  its session-finish hooks, so the JSON report and JUnit are written (exit
  status 2). Installed only on the controller's main thread, and only where
  nobody else installed a handler.
- While the session-finish hooks write the reports, SIGINT and SIGTERM are
  held back: a second Ctrl-C (with ``-n 2``, xdist is then waiting for its
  workers) no longer cuts the writing off. They are reported and dropped.
"""

from __future__ import annotations

import contextlib
import signal
import threading


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where the run is, so pytest ends it as interrupted."""


def _on_term(signum, frame):
    raise Terminated("SIGTERM")


def install_sigterm():
    """The previous SIGTERM handler when ours was installed, else None."""
    if threading.current_thread() is not threading.main_thread():
        return None
    if signal.getsignal(signal.SIGTERM) is not signal.SIG_DFL:
        return None
    signal.signal(signal.SIGTERM, _on_term)
    return signal.SIG_DFL


def restore_sigterm(previous) -> None:
    if previous is not None and threading.current_thread() is threading.main_thread():
        if signal.getsignal(signal.SIGTERM) is _on_term:
            signal.signal(signal.SIGTERM, previous)


@contextlib.contextmanager
def held_back(notes: list):
    """SIGINT and SIGTERM held back (appended to ``notes``) inside the block."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    def hold(signum, frame):
        notes.append(signal.Signals(signum).name)
    old = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        for s in old:
            signal.signal(s, hold)
    except (ValueError, OSError):     # pragma: no cover - not the main interpreter
        yield
        return
    try:
        yield
    finally:
        for s, h in old.items():
            signal.signal(s, h if h is not None else signal.SIG_DFL)
