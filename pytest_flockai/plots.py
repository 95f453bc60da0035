"""Pictures of a flight (optional: needs matplotlib, ``pip install 'pytest-flockai[plots]'``).

- ``energy_figure``: the energy breakdown as in the paper's Figures 5-8: the
  share of motors, processing and communication, and each group's sub-components
  (a fleet: each drone's, stacked);
- ``path_figure``: the flight path seen from above, coloured by flight phase (a
  fleet: one colour per drone), over the world's people, with the ML detections
  when there are any; at least ``MIN_SPAN_M`` wide.

Each ``*_figure(result, path)`` saves the Figure its ``*_fig(result)`` builds
(tests read the Figure's axes back).
- ``save_envelope``: a KPI mapped over altitude x speed (``ml.envelope``) as CSV
  and, with matplotlib, as a heat map.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ._io import atomic_write

__all__ = ["available", "energy_figure", "path_figure", "save_envelope"]


def available() -> bool:
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        return False
    return True


def _plt():
    import matplotlib
    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt
    return plt


_GROUP_COLOURS = {"motors": "#4C72B0", "proc": "#DD8452", "comm": "#55A868"}
#: the smallest side of a flight path picture (m): a hover is a point, not a 1e-14 m axis
MIN_SPAN_M = 4.0


def _save(fig, path) -> Path:
    p = Path(path)
    fig.savefig(p, dpi=110, bbox_inches="tight")
    _plt().close(fig)
    return p


def energy_figure(result, path) -> Path:
    """The energy breakdown picture (``energy_fig``) as a PNG at ``path``."""
    return _save(energy_fig(result), path)


def energy_fig(result):
    """The energy breakdown as a matplotlib Figure: one flight's groups and their
    sub-components, or a fleet's drones side by side (``fleet_energy_fig``)."""
    if getattr(result, "drones", None):
        return fleet_energy_fig(result)
    plt = _plt()
    b = result.energy_breakdown
    tops = [k for k in b if "." not in k]
    total = sum(b[k] for k in tops) or 1.0
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(11, 4.2), gridspec_kw={"width_ratios": [1, 2]})
    shares = [b[k] / total for k in tops]
    ax0.bar(tops, [100 * s for s in shares], color=[_GROUP_COLOURS.get(k, "#8172B3") for k in tops])
    for i, s in enumerate(shares):
        ax0.text(i, 100 * s + 1, f"{100 * s:.1f}%", ha="center", fontsize=9)
    ax0.set_ylabel("share of E_total (%)")
    ax0.set_title(f"E_total = {energy_text(total)}")
    ax0.set_ylim(0, 105)
    # sub-components of each group, as shares of that group (paper Fig. 7 style)
    y = 0
    labels = []
    for g in tops:
        parts = sorted(((k, v) for k, v in b.items() if k.startswith(g + ".") and k.count(".") == 1),
                       key=lambda kv: -kv[1])
        left = 0.0
        for k, v in parts:
            frac = v / b[g] if b[g] else 0.0
            ax1.barh(y, 100 * frac, left=left, color=_GROUP_COLOURS.get(g, "#8172B3"),
                     edgecolor="white", alpha=0.55 + 0.45 * frac)
            if frac > 0.06:
                ax1.text(left + 50 * frac, y, f"{k.split('.', 1)[1]}\n{100 * frac:.0f}%",
                         ha="center", va="center", fontsize=8)
            left += 100 * frac
        labels.append(g)
        y += 1
    ax1.set_yticks(range(len(labels)), labels)
    ax1.set_xlabel("share of the group's energy (%)")
    ax1.set_title("sub-components")
    ax1.set_xlim(0, 100)
    scen = result.scenario
    fig.suptitle(f"{scen.get('drone', {}).get('name', '')}  {scen.get('pilot', {}).get('type', '')}  "
                 f"seed {scen.get('seed')}  flight {result.kpis.get('flight_time_s', 0):.0f} s")
    fig.tight_layout()
    return fig


def energy_text(joules: float) -> str:
    """``43.2 J``, ``3.82 kJ``, ``1.2 MJ``: never ``0.0 kJ`` for a small drone."""
    for unit, f in (("MJ", 1e6), ("kJ", 1e3)):
        if abs(joules) >= f:
            return f"{joules / f:.3g} {unit}"
    return f"{joules:.3g} J"


def fleet_energy_fig(result):
    """A fleet's energy: per drone, motors / processing / communication in kJ, stacked."""
    plt = _plt()
    names = list(result.drones)
    fig, ax = plt.subplots(figsize=(max(6.0, 1.1 * len(names) + 3), 4.2))
    bottom = np.zeros(len(names))
    for g, colour in _GROUP_COLOURS.items():
        vals = np.array([result.drones[n].energy_breakdown.get(g, 0.0) / 1000 for n in names])
        ax.bar(names, vals, bottom=bottom, color=colour, label=g)
        bottom += vals
    ax.set_ylabel("energy (kJ)")
    ax.legend(fontsize=8)
    total = result.kpis.get("fleet.energy_total_j", 1000 * float(bottom.sum()))
    ax.set_title(f"fleet of {len(names)} drones: E_total = {energy_text(total)}, makespan "
                 f"{result.kpis.get('fleet.makespan_s', 0):.0f} s")
    ax.set_ylim(0, max(float(bottom.max()) * 1.12, 1e-3))
    fig.tight_layout()
    return fig


def path_figure(result, path) -> Path:
    """The flight path picture (``path_fig``) as a PNG at ``path``."""
    return _save(path_fig(result), path)


_PHASE_COLOURS = {"takeoff": "#55A868", "hover": "#8172B3", "move": "#4C72B0",
                  "accelerating": "#DD8452", "landing": "#C44E52", "landed": "#000000"}


def drone_colours(n: int) -> list:
    """``n`` distinct colours (tab10, then tab20, then evenly spaced hues)."""
    plt = _plt()
    if n <= 10:
        return [plt.get_cmap("tab10")(i) for i in range(n)]
    if n <= 20:
        return [plt.get_cmap("tab20")(i) for i in range(n)]
    return [plt.get_cmap("hsv")(i / n) for i in range(n)]


def path_fig(result):
    """The flight path seen from above as a Figure: coloured by flight phase (a
    fleet: one colour per drone, with a legend), over the world's people, with the
    detections; the axes span at least ``MIN_SPAN_M`` (a hover is not drawn on a
    1e-14 m axis) at an equal scale."""
    plt = _plt()
    tel = result.telemetry
    fig, ax = plt.subplots(figsize=(6.5, 6))
    xs, ys = [0.0], [0.0]
    people = getattr(result, "people", None)
    if people is not None and len(people):
        ax.scatter(people[:, 0], people[:, 1], s=4, c="#999999", label="people")
        xs += list(people[:, 0])
        ys += list(people[:, 1])
    if "drone" in tel:
        names = list(dict.fromkeys(tel["drone"]))
        for name, c in zip(names, drone_colours(len(names))):
            sel = tel[tel["drone"] == name]
            ax.plot(sel.x, sel.y, "-", lw=1.2, color=c, label=str(name))
    elif "phase" in tel:
        for ph, c in _PHASE_COLOURS.items():
            sel = tel[tel.phase == ph]
            if len(sel):
                ax.scatter(sel.x, sel.y, s=6, c=c, label=ph, zorder=3)
    if "x" in tel and len(tel):
        xs += list(tel.x)
        ys += list(tel.y)
    det = [e for e in result.events if e.get("kind") == "inference" and e.get("detected")]
    if det:
        ax.scatter([e["x"] for e in det], [e["y"] for e in det], marker="*", s=80, c="red",
                   label="detections")
    ax.plot([0], [0], "^", color="#bbbbbb", mec="k", ms=11, label="home", zorder=2)
    if "x" in tel and len(tel) and max(np.ptp(tel.x), np.ptp(tel.y)) < 0.1:
        cm = 100 * max(np.ptp(tel.x), np.ptp(tel.y))
        ax.annotate(f"moved {'less than 1 cm' if cm < 1 else f'{cm:.2g} cm'} horizontally",
                    (0.02, 0.02), xycoords="axes fraction", fontsize=8, color="#555555")
    _square_limits(ax, xs, ys)
    ax.set_xlabel("x east (m)")
    ax.set_ylabel("y north (m)")
    ax.legend(fontsize=8, markerscale=1.5, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    n = tel["drone"].nunique() if "drone" in tel else 0
    ax.set_title(f"flight paths of {n} drones" if n else "flight path")
    fig.tight_layout()
    return fig


def _square_limits(ax, xs, ys) -> None:
    """Equal-scale limits around the data, at least ``MIN_SPAN_M`` wide, 5 % margin."""
    x = np.asarray([v for v in xs if np.isfinite(v)] or [0.0], float)
    y = np.asarray([v for v in ys if np.isfinite(v)] or [0.0], float)
    half = max(np.ptp(x), np.ptp(y), MIN_SPAN_M) / 2 * 1.05
    cx, cy = (x.min() + x.max()) / 2, (y.min() + y.max()) / 2
    ax.set_xlim(cx - half, cx + half)
    ax.set_ylim(cy - half, cy + half)
    ax.set_aspect("equal", adjustable="box")


def save_envelope(df, path, kpi: str = "recall") -> list[Path]:
    """Write an envelope (``ml.envelope.envelope``) as ``<path>.csv`` (atomically) and,
    when matplotlib is installed, a heat map of ``kpi`` as ``<path>.png``."""
    path = Path(path)
    written = [atomic_write(path.with_suffix(".csv"), lambda fh: df.to_csv(fh, index=False))]
    if not available():
        return written
    plt = _plt()
    grid = df.pivot(index="altitude_m", columns="speed_mps", values=kpi)
    fig, ax = plt.subplots(figsize=(5, 3.6))
    im = ax.imshow(grid.to_numpy(), origin="lower", vmin=0, vmax=1, cmap="viridis", aspect="auto")
    ax.set_xticks(range(len(grid.columns)), [f"{c:g}" for c in grid.columns])
    ax.set_yticks(range(len(grid.index)), [f"{i:g}" for i in grid.index])
    ax.set_xlabel("speed during the exposure (m/s)")
    ax.set_ylabel("altitude (m)")
    for (i, j), v in np.ndenumerate(grid.to_numpy()):
        ax.text(j, i, f"{v:.2f}", ha="center", va="center", color="w", fontsize=8)
    fig.colorbar(im, label=kpi)
    fig.tight_layout()
    png = path.with_suffix(".png")
    fig.savefig(png, dpi=100)
    plt.close(fig)
    return written + [png]
