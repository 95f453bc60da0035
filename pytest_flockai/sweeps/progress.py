"""A sweep's progress bar: drone-seconds simulated so far and an estimate of
those to go (tqdm), with the variants counted beside it.

A variant's expected simulated time is its numeric ``until`` (the variant's,
else the base mission's); a variant flown to ``"landed"`` or a battery state
is expected to take the mean of the variants finished so far. Cached variants
count as done before the bar starts, so the rate and the time to go are those
of the variants actually flown.

``progress=None`` (the default) shows the bar when the standard error is a
terminal and the sweep has run for ``DELAY_S`` (short sweeps stay quiet),
unless the environment variable ``FLOCKAI_PROGRESS`` is ``0``;
``progress=True`` always shows it (from the start), ``False`` never.
"""

from __future__ import annotations

import math
import os
import sys
from numbers import Real

from tqdm import tqdm

from ..errors import ConfigError

#: s: a sweep shorter than this shows no bar (progress=None)
DELAY_S = 2.0


def check(progress) -> None:
    """ConfigError for a ``progress`` that is not None, True or False."""
    if progress is not None and not isinstance(progress, bool):
        raise ConfigError(f"sweep: progress = {progress!r} is not allowed; expected None "
                          f"(a bar when the terminal shows one), True or False")


def wanted(progress: bool | None, stream=None) -> bool:
    """Whether to show a bar for the setting ``progress`` on ``stream`` (stderr)."""
    if progress is not None:
        return progress
    stream = sys.stderr if stream is None else stream
    if os.environ.get("FLOCKAI_PROGRESS", "").strip() == "0":
        return False
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


def expected_s(base_until, values: dict) -> float | None:
    """s of simulated time a variant is expected to take, None when unknown."""
    until = values.get("until", base_until)
    if isinstance(until, Real) and not isinstance(until, bool) and math.isfinite(until):
        return float(until)
    return None


class Progress:
    """The bar of one sweep (no bar at all when not ``shown``)."""

    def __init__(self, expected: dict, shown: bool, *, delay_s: float = DELAY_S, done: int = 0):
        self.expected = dict(expected)        # index -> s (None: unknown) of the variants to go
        self.flown_s: list[float] = []
        self.done, self.total = done, done + len(self.expected)
        self.bar = None
        if shown and self.expected:
            self.bar = tqdm(total=self._total_s(0.0), initial=0.0, unit="drone-s",
                            unit_scale=True, desc="sweep", delay=delay_s, file=sys.stderr,
                            dynamic_ncols=True,
                            bar_format="{desc}: {percentage:3.0f}%|{bar}| {n_fmt}/{total_fmt} "
                                       "drone-s [{elapsed}<{remaining}, {rate_fmt}{postfix}]")
            self.bar.set_postfix_str(self._count(), refresh=False)

    def _total_s(self, flown: float) -> float | None:
        known = [s for s in self.expected.values() if s is not None]
        unknown = len(self.expected) - len(known)
        if unknown and not self.flown_s:
            return None
        mean = sum(self.flown_s) / len(self.flown_s) if self.flown_s else 0.0
        return flown + sum(known) + unknown * mean

    def _count(self) -> str:
        return f"{self.done}/{self.total} variants"

    def update(self, index: int, sim_time_s) -> None:
        """Variant ``index`` finished after ``sim_time_s`` s of simulated time."""
        self.expected.pop(index, None)
        self.done += 1
        s = float(sim_time_s) if isinstance(sim_time_s, Real) else 0.0
        s = s if math.isfinite(s) else 0.0
        self.flown_s.append(s)
        if self.bar is None:
            return
        self.bar.total = self._total_s(self.bar.n + s)
        self.bar.set_postfix_str(self._count(), refresh=False)
        self.bar.update(s)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None
