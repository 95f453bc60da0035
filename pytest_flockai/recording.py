"""Where completed flights go: a sink per context, not a global list.

``Mission.run()`` hands every flight it completes (and the partial result of
one that ended in a ``SimulationError``) to ``publish``. Nothing receives it
unless a caller opened ``recording(sink)``; the pytest plugin opens one per
test, and a notebook can open one to log its flights::

    with fa.recording(lambda result, mission: log.append(result)):
        fa.Mission(...).run()

The sink lives in a ``contextvars.ContextVar``: nested recordings (a pytester
session inside a test) stack and unwind by themselves, and threads or asyncio
tasks each see their own.

Budgets checked in a test body (``budgets.check`` / ``budgets.evaluate``) go
the same way to a ``checking(sink)`` context: the plugin keeps them with the
test, so the reports show the budgets of a test that flies nothing.
"""

from __future__ import annotations

from contextlib import contextmanager
from contextvars import ContextVar
from typing import Callable

from .errors import ConfigError

#: fn(result, mission) -> None
FlightSink = Callable[[object, object], None]

_SINK: ContextVar[FlightSink | None] = ContextVar("pytest_flockai_flight_sink", default=None)

#: fn(result, verdicts) -> None
CheckSink = Callable[[object, list], None]

_CHECKS: ContextVar[CheckSink | None] = ContextVar("pytest_flockai_check_sink", default=None)


@contextmanager
def recording(sink: FlightSink):
    """Send every flight completed inside the ``with`` block to ``sink(result, mission)``."""
    if not callable(sink):
        raise ConfigError(f"recording: sink = {sink!r} is not callable; expected "
                          f"fn(result, mission)")
    token = _SINK.set(sink)
    try:
        yield sink
    finally:
        _SINK.reset(token)


def publish(result, mission) -> None:
    """Hand a completed flight to the sink of the current context, if any."""
    sink = _SINK.get()
    if sink is not None:
        sink(result, mission)


@contextmanager
def checking(sink: CheckSink):
    """Send the verdicts of every ``budgets.evaluate``/``check`` call inside the
    ``with`` block to ``sink(result, verdicts)``."""
    if not callable(sink):
        raise ConfigError(f"checking: sink = {sink!r} is not callable; expected "
                          f"fn(result, verdicts)")
    token = _CHECKS.set(sink)
    try:
        yield sink
    finally:
        _CHECKS.reset(token)


def publish_verdicts(result, verdicts: list) -> None:
    """Hand the verdicts of a budget check to the check sink of the current context, if any."""
    sink = _CHECKS.get()
    if sink is not None:
        sink(result, verdicts)
