"""Flight components that misbehave in chosen sweep variants (tests of the sweep
engine). A module of their own, so that spawned pool workers and Dask workers
can import them (``PYTHONPATH`` holds ``tests/``)."""

import os
import time
from pathlib import Path

import pytest_flockai as fa


class _OnPayload(fa.Clocked):
    """Does ``act()`` once, in the flights whose payload is ``payload_kg``."""
    period_s = 0.5

    def __init__(self, payload_kg):
        self.payload_kg = payload_kg

    def bind(self, run):
        super().bind(run)
        self.run = run

    def step(self, t):
        self.advance_clock()
        if self.run.mission.drone.payload_kg == self.payload_kg:
            self.act()


class RaiseOn(_OnPayload):
    """A bug in user code: a ZeroDivisionError in one variant."""

    def act(self):
        return 1 / 0


class ExitOn(_OnPayload):
    """A worker that dies: ``os._exit(code)`` in one variant."""

    def __init__(self, payload_kg, code=9):
        super().__init__(payload_kg)
        self.code = code

    def act(self):
        os._exit(self.code)


class InterruptOn(_OnPayload):
    """Ctrl-C during one variant (workers=1)."""

    def act(self):
        raise KeyboardInterrupt


class MarkAndWait(_OnPayload):
    """Writes ``<folder>/<pid>`` and waits ``wait_s`` (wall time, no change to the
    flight) in one variant: a test kills that worker while it waits."""

    def __init__(self, payload_kg, folder, wait_s):
        super().__init__(payload_kg)
        self.folder, self.wait_s, self.done = str(folder), wait_s, False

    def bind(self, run):
        super().bind(run)
        self.done = False

    def act(self):
        if not self.done:
            self.done = True
            Path(self.folder, str(os.getpid())).write_text("flying")
            time.sleep(self.wait_s)
