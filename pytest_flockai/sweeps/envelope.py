"""A sweep's envelope on disk: the DataFrame as CSV and, when matplotlib is
installed (``pip install 'pytest-flockai[plots]'``), a picture of one KPI over
two axes (a heat map of the mean over the other axes for a grid, a scatter for
random or Latin-hypercube samples); variants that broke a budget are crossed."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._io import atomic_write
from ..plots import available


def label(row, axis_names) -> str:
    """A variant as text: ``payload_kg=0.2, wind_mps=6``."""
    return ", ".join(f"{a}={_fmt(row[a])}" for a in axis_names)


def _fmt(v) -> str:
    return f"{v:.4g}" if isinstance(v, float) else str(v)


def save(df, path, x: str, y: str, kpi: str) -> list[Path]:
    """Write ``<path>.csv`` (atomically) and, with matplotlib, ``<path>.png``."""
    path = Path(path)
    written = [atomic_write(path.with_suffix(".csv"), lambda fh: df.to_csv(fh, index=False))]
    if not available() or kpi not in df or df[kpi].isna().all():
        return written
    import matplotlib
    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(5.5, 4))
    if df.attrs.get("method", "grid") == "grid":
        grid = df.pivot_table(index=y, columns=x, values=kpi, aggfunc="mean")
        im = ax.imshow(grid.to_numpy(dtype=float), origin="lower", cmap="viridis", aspect="auto")
        ax.set_xticks(range(len(grid.columns)), [_fmt(c) for c in grid.columns])
        ax.set_yticks(range(len(grid.index)), [_fmt(i) for i in grid.index])
        for (i, j), v in np.ndenumerate(grid.to_numpy(dtype=float)):
            ax.text(j, i, f"{v:.3g}", ha="center", va="center", color="w", fontsize=7)
        if "ok" in df:
            bad = df[~df["ok"].astype(bool)]
            cols, rows = list(grid.columns), list(grid.index)
            ax.scatter([cols.index(v) for v in bad[x]], [rows.index(v) for v in bad[y]],
                       marker="x", color="red", s=60, label="budget broken")
    else:
        im = ax.scatter(df[x], df[y], c=df[kpi], cmap="viridis", s=30)
        if "ok" in df:
            bad = df[~df["ok"].astype(bool)]
            ax.scatter(bad[x], bad[y], marker="x", color="red", s=60, label="budget broken")
    if "ok" in df and not df["ok"].all():
        ax.legend(loc="upper right", fontsize=7)
    ax.set_xlabel(x)
    ax.set_ylabel(y)
    fig.colorbar(im, label=kpi)
    fig.tight_layout()
    png = path.with_suffix(".png")
    atomic_write(png, lambda fh: fig.savefig(fh, dpi=100, format="png"), text=False)
    plt.close(fig)
    return written + [png]


def summary(df, files=()) -> dict:
    """A sweep as plain JSON data: its settings, counts and every row."""
    rows = df.astype(object).where(df.notna(), None).to_dict("records")
    keep = ("axes", "method", "samples", "seed", "budgets", "workers", "backend", "executor",
            "interrupted")
    return {**{k: df.attrs.get(k) for k in keep}, "variants": len(df),
            "broken": int((~df["ok"].astype(bool)).sum()) if "ok" in df else 0,
            "files": [str(f) for f in files], "rows": rows}
