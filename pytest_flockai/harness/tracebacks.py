"""Tracebacks pytest can format, whatever instruction an exception interrupted.

CPython 3.11 gives a few compiler-made instructions no line number (the jump
back at the end of a ``for`` body whose last statement is an ``if``, as in the
flight loop, ``mission/loop.py``). An exception raised there by a signal
handler (pytest-timeout's ``method="signal"``, a SIGALRM of the user's own) has
a traceback entry with ``tb_lineno`` None, and pytest (8.0 to 9.2) crashes with
an INTERNALERROR formatting it ("unsupported operand type(s) for -: 'NoneType'
and 'int'"), so the session ends without a result for the test. Seen in our CI
about once in 20 runs of ``tests/harness/test_rerun_timeout.py``.

``RepairPlugin`` wraps setup, call and teardown and gives every such entry the
line of the nearest instruction before it that has one (``co_lines``).
"""

from __future__ import annotations

import types

import pytest


def _line_before(code, lasti: int) -> int:
    line = code.co_firstlineno
    for start, _end, lineno in code.co_lines():
        if start > lasti:
            break
        if lineno is not None:
            line = lineno
    return line


def _repaired_tb(tb):
    entries = []
    while tb is not None:
        entries.append(tb)
        tb = tb.tb_next
    if all(e.tb_lineno is not None for e in entries):
        return None
    new = None
    for e in reversed(entries):
        line = e.tb_lineno
        if line is None:
            line = _line_before(e.tb_frame.f_code, e.tb_lasti)
        new = types.TracebackType(new, e.tb_frame, e.tb_lasti, line)
    return new


def repair(exc: BaseException) -> BaseException:
    """``exc`` (and the exceptions it chains to) with every traceback entry given a
    line number; entries that had one are kept as they were."""
    todo: list[BaseException | None] = [exc]
    seen: set[int] = set()
    while todo:
        e = todo.pop()
        if e is None or id(e) in seen:
            continue
        seen.add(id(e))
        tb = _repaired_tb(e.__traceback__)
        if tb is not None:
            e.__traceback__ = tb
        todo += [e.__cause__, e.__context__]
    return exc


class RepairPlugin:
    """Registered by the plugin as ``flockai-tracebacks``."""

    @staticmethod
    def _wrapped():
        try:
            return (yield)
        except BaseException as exc:
            repair(exc)
            raise

    @pytest.hookimpl(wrapper=True, tryfirst=True)
    def pytest_runtest_setup(self, item):
        return (yield from self._wrapped())

    @pytest.hookimpl(wrapper=True, tryfirst=True)
    def pytest_runtest_call(self, item):
        return (yield from self._wrapped())

    @pytest.hookimpl(wrapper=True, tryfirst=True)
    def pytest_runtest_teardown(self, item, nextitem):
        return (yield from self._wrapped())
