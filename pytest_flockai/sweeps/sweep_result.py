"""The DataFrame ``fa.sweep`` returns: a plain pandas DataFrame (one row per
variant, the settings in ``attrs``) that shows in a notebook as a compact
summary: its axes, budgets, broken variants and first rows
(``notebook.sweep_html``). What is derived from it (``df.pivot``, a column
selection) is a plain DataFrame again."""

from __future__ import annotations

import pandas as pd

from .. import notebook as _notebook


class SweepResult(pd.DataFrame):
    """A sweep's DataFrame with a notebook summary."""

    @property
    def _constructor(self):
        return pd.DataFrame

    @classmethod
    def of(cls, df: pd.DataFrame) -> SweepResult:
        """``df`` (and its attrs) as a SweepResult."""
        out = cls(df)
        out.attrs = dict(df.attrs)
        return out

    def _repr_html_(self) -> str:
        return _notebook.sweep_html(self)
