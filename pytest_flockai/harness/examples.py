"""Hypothesis tests: every example the test body runs is counted, so the
recorder can keep the failing (shrunk) example's flights in full and the
rest as a count and a KPI range (``TestState.compact_examples``).

Hypothesis lets plugins wrap the function it calls once per example
(``test.hypothesis.inner_test``); the wrapper only counts and is removed
after the test.
"""

from __future__ import annotations

import contextlib
import functools


@contextlib.contextmanager
def counted(item, st):
    handle = getattr(getattr(item, "obj", None), "hypothesis", None)
    inner = getattr(handle, "inner_test", None)
    if inner is None:
        yield
        return

    @functools.wraps(inner)
    def one_example(*args, **kwargs):
        st.next_example()
        return inner(*args, **kwargs)

    handle.inner_test = one_example
    try:
        yield
    finally:
        handle.inner_test = inner
