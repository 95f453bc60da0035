"""Signals, so an interrupted run still leaves its reports.

- SIGTERM (a CI runner cancelling the job, ``timeout``, ``kill``) ends the run
  the way Ctrl-C does: pytest stops, marks the session interrupted and runs
  its session-finish hooks, so the JSON report and JUnit are written (exit
  status 2). Installed only on the controller's main thread, and only where
  nobody else installed a handler.
- From the first Ctrl-C (or the session's end) until the session-finish hooks
  have written the reports, one more SIGINT or SIGTERM is held back and
  reported: a second Ctrl-C (with ``-n 2``, while pytest formats the interrupt
  or xdist waits for its workers) no longer cuts the writing off. A third one
  stops the run at once, so a hung shutdown can still be left.
"""

from __future__ import annotations

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


class Holder:
    """SIGINT and SIGTERM held back (their names appended to ``notes``) from
    ``start()`` (the first Ctrl-C, or the session's end) to ``stop()`` (the
    reports written); a third one while held stops the run at once."""

    def __init__(self, notes: list):
        self.notes = notes
        self.old: dict | None = None

    def start(self) -> None:
        if self.old is not None or threading.current_thread() is not threading.main_thread():
            return
        old = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
        try:
            for s in old:
                signal.signal(s, self._hold)
        except (ValueError, OSError):     # pragma: no cover - not the main interpreter
            return
        self.old = old

    def _hold(self, signum, frame):
        self.notes.append(signal.Signals(signum).name)
        if len(self.notes) >= 2:
            self.stop()
            raise KeyboardInterrupt(f"{signal.Signals(signum).name} while the reports were written")

    def stop(self) -> None:
        if self.old is None:
            return
        for s, h in self.old.items():
            signal.signal(s, h if h is not None else signal.SIG_DFL)
        self.old = None
