"""Which variants a sweep flies: a full-factorial grid, random samples or a
Latin hypercube (``scipy.stats.qmc.LatinHypercube``), from a seed.

- ``method="grid"``: every axis is a list (or 1-D array) of values; the
  variants are every combination, the first axis varying slowest.
- ``method="random"`` / ``"lhs"`` with ``samples=N``: an axis is a range
  ``(low, high)`` (a tuple of two numbers, drawn uniformly; integers for
  ``mission_seed``) or a list of choices (drawn with equal probability).

Every bad axis raises a ``ConfigError`` naming the axis, the value and what is
allowed; so does a sweep of more than ``limits.MAX_VARIANTS`` variants, before
any of them is made. Same seed, same variants.
"""

from __future__ import annotations

import itertools
import math
from numbers import Integral, Real
from typing import Any

import numpy as np

from .. import limits
from ..errors import ConfigError
from .axes import INTEGER_AXES

METHODS = ("grid", "random", "lhs")


def _values(name, spec, method) -> list:
    if isinstance(spec, (str, bytes, dict, set)) or not hasattr(spec, "__len__") \
            or isinstance(spec, Real):
        raise ConfigError(f"sweep: axis {name} = {spec!r} is not allowed; expected a list or 1-D "
                          f"array of values" + ("" if method == "grid"
                                                else " or a range (low, high)"))
    arr = np.asarray(spec, dtype=object)
    if arr.ndim != 1:
        raise ConfigError(f"sweep: axis {name} = {spec!r} has shape {arr.shape}; expected a "
                          f"flat list (1-D) of values")
    if len(arr) == 0:
        raise ConfigError(f"sweep: axis {name} is empty; expected at least one value")
    return [v.item() if isinstance(v, np.generic) else v for v in arr]


def _range(name, spec) -> tuple[float, float]:
    if len(spec) != 2:
        raise ConfigError(f"sweep: axis {name} = {spec!r} has {len(spec)} entries; a range is a "
                          f"tuple (low, high); write a list for choices")
    lo, hi = spec
    for v in (lo, hi):
        if isinstance(v, bool) or not isinstance(v, Real) or not math.isfinite(v):
            raise ConfigError(f"sweep: axis {name} = {spec!r}: {v!r} is not a finite number; a "
                              f"range is a tuple (low, high) of numbers")
    if hi < lo:
        raise ConfigError(f"sweep: axis {name} = {spec!r}: high < low; expected (low, high)")
    if name in INTEGER_AXES and not all(isinstance(v, Integral) for v in (lo, hi)):
        raise ConfigError(f"sweep: axis {name} = {spec!r}: expected a range of integers")
    return float(lo), float(hi)


def check_samples(method, samples):
    if method not in METHODS:
        raise ConfigError(f"sweep: method = {method!r} is not allowed; allowed: "
                          f"{', '.join(METHODS)}")
    if method == "grid":
        if samples is not None:
            raise ConfigError(f"sweep: samples = {samples!r} is not allowed with method='grid' "
                              f"(the grid has every combination); use method='random' or 'lhs'")
        return None
    if isinstance(samples, bool) or not isinstance(samples, Integral) or samples < 1:
        raise ConfigError(f"sweep: samples = {samples!r} is not allowed with method={method!r}; "
                          f"expected an integer >= 1")
    return int(samples)


def variants(axes: dict, method: str, samples, seed) -> tuple[list[dict], dict]:
    """(the variants as dicts {axis: value}, the values to check per axis)."""
    try:
        return _variants(axes, method, samples, seed)
    except MemoryError:
        raise ConfigError(f"sweep: the variants of method={method!r}, samples={samples!r} do not "
                          f"fit in this machine's memory (was fa.limits.MAX_VARIANTS = "
                          f"{limits.MAX_VARIANTS:,} raised?); sweep fewer") from None


def _variants(axes: dict, method: str, samples, seed) -> tuple[list[dict], dict]:
    samples = check_samples(method, samples)
    if isinstance(seed, bool) or not isinstance(seed, Integral) or seed < 0:
        raise ConfigError(f"sweep: seed = {seed!r} is not allowed; expected an integer >= 0")
    if not axes:
        raise ConfigError("sweep: no axis given; write e.g. payload_kg=[0.0, 0.2, 0.4]")
    names = list(axes)
    if method == "grid":
        levels = [_values(n, axes[n], method) for n in names]
        check_count(math.prod(len(v) for v in levels),
                    " x ".join(f"{len(v)} {n}" for n, v in zip(names, levels)))
        return ([dict(zip(names, combo)) for combo in itertools.product(*levels)],
                dict(zip(names, levels)))
    specs: list[tuple[str, Any]] = []
    to_check: dict[str, Any] = {}
    for n in names:
        spec = axes[n]
        if isinstance(spec, tuple):
            specs.append(("range", _range(n, spec)))
            to_check[n] = list(spec)
        else:
            specs.append(("choice", _values(n, spec, method)))
            to_check[n] = specs[-1][1]
    check_count(samples, f"samples = {samples:,}")
    rng = np.random.default_rng(int(seed))
    if method == "random":
        u = rng.random((samples, len(names)))
    else:
        # scipy.stats takes ~1 s to import: loaded here, not with the package
        from scipy.stats import qmc
        u = qmc.LatinHypercube(d=len(names), rng=rng).random(samples)
    out = []
    for row in u:
        out.append({n: _pick(n, kind, spec, x) for n, (kind, spec), x in zip(names, specs, row)})
    return out, to_check


def check_count(count: int, what: str) -> None:
    """ConfigError when a sweep of ``count`` variants (``what`` makes them) is above the limit."""
    if count > limits.MAX_VARIANTS:
        raise ConfigError(f"sweep: {count:,} variants ({what}) is above the limit "
                          f"pytest_flockai.limits.MAX_VARIANTS = {limits.MAX_VARIANTS:,}; "
                          f"sweep fewer values or samples, or raise the limit at your own risk "
                          f"(fa.limits.MAX_VARIANTS = {count})")


def _pick(name, kind, spec, x):
    if kind == "choice":
        return spec[min(int(x * len(spec)), len(spec) - 1)]
    lo, hi = spec
    if name in INTEGER_AXES:
        return int(min(math.floor(lo + x * (hi - lo + 1)), hi))
    return float(lo + x * (hi - lo))
