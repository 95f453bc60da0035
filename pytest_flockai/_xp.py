"""The array namespace the shared formulas take (``xp``), as array-API code does.

A formula written once is called by the core with ``MATH`` (Python floats: the
flight loop's scalars, where a numpy call costs more than the arithmetic) and by
the batched backend with ``jax.numpy`` (the batched modules pass ``jnp``). The
formula uses only the names below, which both provide with the same meaning;
``where(c, a, b)`` evaluates both branches in either namespace, so a formula
guards its own domains (``maximum(x, 0)`` before a square root) instead of
relying on an ``if``.
"""

from __future__ import annotations

import math


def _where(cond, a, b):
    return a if cond else b


def _clip(x, lo, hi):
    return min(hi, max(lo, x))


class _Math:
    """``math`` with the array-namespace names the shared formulas use (scalars)."""

    __slots__ = ()
    exp = staticmethod(math.exp)
    sqrt = staticmethod(math.sqrt)
    abs = staticmethod(abs)
    maximum = staticmethod(max)
    minimum = staticmethod(min)
    where = staticmethod(_where)
    clip = staticmethod(_clip)
    pi = math.pi


#: the scalar namespace: ``math`` plus ``where``, ``maximum``, ``minimum``, ``clip``
MATH = _Math()
