"""A sweep's envelope on disk: the DataFrame as CSV and, when matplotlib is
installed (``pip install 'pytest-flockai[plots]'``), a picture of one KPI over
two axes (a heat map of the mean over the other axes for a grid, a scatter for
random or Latin-hypercube samples), in the KPI's unit (the budget's: minutes
for ``>= 15 min``), with the budget's limit as a red contour; variants that
broke a budget are crossed."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .. import budgets as _budgets
from .. import kpis as _kpis
from .._io import atomic_write
from ..errors import ConfigError
from ..plots import available


def label(row, axis_names) -> str:
    """A variant as text: ``payload_kg=0.2, wind_mps=6``."""
    return ", ".join(f"{a}={_fmt(row[a])}" for a in axis_names)


def _fmt(v) -> str:
    return f"{v:.4g}" if isinstance(v, float) else str(v)


def save(df, path, x: str, y: str, kpi: str) -> list[Path]:
    """Write ``<path>.csv`` (atomically) and, with matplotlib, ``<path>.png`` (``figure``)."""
    path = Path(path)
    written = [atomic_write(path.with_suffix(".csv"), lambda fh: df.to_csv(fh, index=False))]
    if not available() or kpi not in df or df[kpi].isna().all():
        return written
    fig = figure(df, x, y, kpi)
    png = path.with_suffix(".png")
    atomic_write(png, lambda fh: fig.savefig(fh, dpi=100, format="png"), text=False)
    _plt().close(fig)
    return written + [png]


def _plt():
    import matplotlib
    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt
    return plt


def display_unit(kpi: str, values, budget=None) -> tuple[str, float]:
    """(unit label, factor): shown value = SI value / factor. The budget's unit when
    it has one (``>= 15 min``: min), else the KPI's, in minutes past 2 minutes and
    in percent for fractions."""
    if budget is not None and budget.unit and budget.unit != "%":
        return budget.unit, budget.factor
    info = _kpis.get(kpi)
    unit = info.unit if info is not None else ""
    if unit == "fraction" or (budget is not None and budget.unit == "%"):
        return "%", 0.01
    if unit == "s" and np.nanmax(np.abs(np.asarray(values, float))) >= 120:
        return "min", 60.0
    return ("" if unit in ("1", "count") else unit), 1.0


def _budget(df, kpi):
    text = (df.attrs.get("budgets") or {}).get(kpi)
    if not text:
        return None
    try:
        return _budgets.parse(kpi, text)
    except ConfigError:
        return None


def figure(df, x: str, y: str, kpi: str):
    """One KPI over two axes as a Figure, in the KPI's display unit (``display_unit``),
    with the budget's limit drawn as a contour (a grid) and the variants that broke it
    crossed."""
    plt = _plt()
    budget = _budget(df, kpi)
    label, factor = display_unit(kpi, df[kpi], budget)
    fig, ax = plt.subplots(figsize=(5.5, 4))
    if df.attrs.get("method", "grid") == "grid":
        grid = df.pivot_table(index=y, columns=x, values=kpi, aggfunc="mean")
        z = grid.to_numpy(dtype=float) / factor
        im = ax.imshow(z, origin="lower", cmap="viridis", aspect="auto")
        ax.set_xticks(range(len(grid.columns)), [_fmt(c) for c in grid.columns])
        ax.set_yticks(range(len(grid.index)), [_fmt(i) for i in grid.index])
        for (i, j), v in np.ndenumerate(z):
            ax.text(j, i, f"{v:.3g}", ha="center", va="center", color="w", fontsize=7)
        if budget is not None and min(z.shape) >= 2 and np.nanmin(z) < budget.limit / factor \
                < np.nanmax(z):
            ax.contour(z, levels=[budget.limit / factor], colors="red", linewidths=1.5)
            ax.plot([], [], color="red", lw=1.5, label=f"budget {budget.text}")
        bad = df[~df["ok"].astype(bool)] if "ok" in df else df.iloc[:0]
        if len(bad):
            cols, rows = list(grid.columns), list(grid.index)
            ax.scatter([cols.index(v) for v in bad[x]], [rows.index(v) for v in bad[y]],
                       marker="x", color="red", s=60, label="budget broken")
    else:
        im = ax.scatter(df[x], df[y], c=df[kpi] / factor, cmap="viridis", s=30)
        bad = df[~df["ok"].astype(bool)] if "ok" in df else df.iloc[:0]
        if len(bad):
            ax.scatter(bad[x], bad[y], marker="x", color="red", s=60, label="budget broken")
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="upper right", fontsize=7)
    ax.set_xlabel(x)
    ax.set_ylabel(y)
    fig.colorbar(im, label=f"{kpi} ({label})" if label else kpi)
    if budget is not None:
        ax.set_title(f"{kpi} {budget.text}", fontsize=10)
    fig.tight_layout()
    return fig


def summary(df, files=()) -> dict:
    """A sweep as plain JSON data: its settings, counts and every row."""
    rows = df.astype(object).where(df.notna(), None).to_dict("records")
    keep = ("axes", "method", "samples", "seed", "budgets", "workers", "backend", "executor",
            "interrupted")
    return {**{k: df.attrs.get(k) for k in keep}, "variants": len(df),
            "broken": int((~df["ok"].astype(bool)).sum()) if "ok" in df else 0,
            "files": [str(f) for f in files], "rows": rows}
