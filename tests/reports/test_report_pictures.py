"""The pictures in the reports, read back from the matplotlib Figures they draw: a
hover's path on sensible axes, one colour per fleet drone with a legend, the
fleet's energy, a sweep heat map in the budget's unit with its contour, the
history trend with commit labels and a distinct style per series."""

import numpy as np
import pandas as pd
import pytest

import pytest_flockai as fa
from pytest_flockai import plots
from pytest_flockai.reports import history
from pytest_flockai.sweeps import envelope_files as envelope

matplotlib = pytest.importorskip("matplotlib")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.contour import ContourSet  # noqa: E402

MAVIC = "dji-mavic-2-pro"


@pytest.fixture(scope="module")
def hover():
    return fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=1.0)).run()


@pytest.fixture(scope="module")
def fleet():
    pilots = [fa.pilots.Waypoints([(x, 0, 5), (x, 10, 5)], speed=5.0) for x in (0.0, 10.0, 20.0)]
    return fa.Fleet([fa.FleetDrone(f"drone-{i + 1}", fa.drone(MAVIC), p, pad=(10.0 * i, 0),
                                   seed=i) for i, p in enumerate(pilots)]).run()


def test_a_hover_is_drawn_on_axes_a_few_metres_wide(hover):
    tel = hover.telemetry
    assert np.ptp(tel.x) < 0.01 and np.ptp(tel.y) < 0.01          # it barely moves
    fig = plots.path_fig(hover)
    ax = fig.axes[0]
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    assert x1 - x0 >= plots.MIN_SPAN_M and y1 - y0 == pytest.approx(x1 - x0)
    assert x0 < 0 < x1 and y0 < 0 < y1                               # home and the drone
    assert ax.get_title() == "flight path"
    assert [t.get_text() for t in ax.texts] == ["moved less than 1 cm horizontally"]
    hover_pts = [c for c in ax.collections if c.get_label() == "hover"]
    assert hover_pts and hover_pts[0].get_zorder() > 2            # drawn over the home mark
    plt.close(fig)
    fig = plots.energy_fig(hover)
    assert fig.axes[0].get_title().startswith("E_total = ") and \
        fig.axes[0].get_title().endswith(" J")                    # not "0.0 kJ"
    plt.close(fig)


def test_fleet_paths_one_colour_per_drone_with_a_legend(fleet):
    fig = plots.path_fig(fleet)
    ax = fig.axes[0]
    lines = {ln.get_label(): ln for ln in ax.get_lines()}
    drones = ["drone-1", "drone-2", "drone-3"]
    assert all(d in lines for d in drones)
    colours = {matplotlib.colors.to_hex(lines[d].get_color()) for d in drones}
    assert len(colours) == 3
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert drones == [t for t in legend if t.startswith("drone-")]
    x0, x1 = ax.get_xlim()
    assert x0 <= 0 and x1 >= 20                                      # every drone's leg
    assert ax.get_title() == "flight paths of 3 drones"
    plt.close(fig)


def test_the_fleet_energy_picture_shows_each_drone(fleet):
    fig = plots.energy_fig(fleet)
    ax = fig.axes[0]
    ticks = [t.get_text() for t in ax.get_xticklabels()]
    assert ticks == ["drone-1", "drone-2", "drone-3"]
    heights = {}
    for c in ax.containers:
        for name, bar in zip(ticks, c):
            heights[name] = heights.get(name, 0.0) + bar.get_height()
    assert sum(heights.values()) == pytest.approx(fleet.kpis["fleet.energy_total_j"] / 1000,
                                                   rel=1e-3)
    assert all(h > 0 for h in heights.values())
    title = ax.get_title()
    assert title.startswith("fleet of 3 drones: E_total = ") and "0.0 kJ" not in title
    assert "seed None" not in title
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["motors", "proc", "comm"]
    plt.close(fig)


def _sweep_df():
    rows = []
    for payload in (0.0, 0.25, 0.5):
        for wind in (0.0, 5.0, 10.0):
            end = 1800.0 - 1200.0 * payload - 20.0 * wind       # s
            rows.append({"payload_kg": payload, "wind_mps": wind, "endurance_s": end,
                         "ok": end >= 1200.0})
    df = pd.DataFrame(rows)
    df.attrs.update(method="grid", axes=["payload_kg", "wind_mps"],
                    budgets={"endurance_s": ">= 20 min"})
    return df


def test_the_sweep_heat_map_is_in_the_budget_unit_with_its_contour():
    df = _sweep_df()
    fig = envelope.figure(df, "payload_kg", "wind_mps", "endurance_s")
    ax, cbar = fig.axes
    assert cbar.get_ylabel() == "endurance_s (min)"
    texts = sorted(float(t.get_text()) for t in ax.texts)
    assert texts[-1] == pytest.approx(30.0) and texts[0] == pytest.approx(16.7, abs=0.05)
    contours = [c for c in ax.collections if isinstance(c, ContourSet)]
    if contours:            # matplotlib >= 3.8: the ContourSet is itself the axes' collection
        assert len(contours) == 1 and list(contours[0].levels) == [20.0]
    else:                   # 3.7 (the lowest allowed): the contour's lines are a PathCollection
        assert len(ax.collections) == 2            # beside the broken variants' markers
    legend = [t.get_text() for t in ax.get_legend().get_texts()]
    assert legend == ["budget >= 20 min", "budget broken"]
    assert ax.get_title() == "endurance_s >= 20 min"
    plt.close(fig)
    df["ok"] = True                                    # nothing broken: no such legend entry
    fig = envelope.figure(df, "payload_kg", "wind_mps", "endurance_s")
    assert [t.get_text() for t in fig.axes[0].get_legend().get_texts()] == ["budget >= 20 min"]
    plt.close(fig)


def test_the_sweep_heat_map_without_a_budget_uses_minutes_for_long_times():
    df = _sweep_df()
    df.attrs["budgets"] = {}
    fig = envelope.figure(df.drop(columns="ok"), "payload_kg", "wind_mps", "endurance_s")
    ax, cbar = fig.axes
    assert cbar.get_ylabel() == "endurance_s (min)"
    assert not [c for c in ax.collections if isinstance(c, ContourSet)]
    assert "e+" not in "".join(t.get_text() for t in ax.texts)
    plt.close(fig)


def test_history_trend_labels_commits_and_styles_every_series():
    runs = []
    for i, commit in enumerate(["0123456789ab", "abcdef012345", None]):
        runs.append({"created": f"2026-11-2{i}T10:00:00+00:00", "commit": commit,
                     "tag": "v0.2.0" if i == 1 else None, "dirty": False, "tests": {
                         f"tests/test_suite_with_a_long_path.py::test_flight_{k:02d}[case]":
                             {"flight": {"endurance_s": 1000.0 + k + i}} for k in range(12)}})
    fig = history.trend_fig(runs, "endurance_s")
    ax = fig.axes[0]
    assert [t.get_text() for t in ax.get_xticklabels()] == ["0123456", "v0.2.0", "11-22 10:00"]
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert len(labels) == 12 and labels[0] == "test_flight_00[case] / flight"
    styles = {(matplotlib.colors.to_hex(ln.get_color()), ln.get_linestyle(), ln.get_marker())
              for ln in ax.get_lines()}
    assert len(styles) == 12
    assert ax.get_ylabel() == "endurance_s (s)"
    plt.close(fig)
    assert history.series_label("a.py::" + "x" * 80 + " / flight", 30).count("\u2026") == 1
