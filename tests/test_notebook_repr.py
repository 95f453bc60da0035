"""Results in a notebook (``_repr_html_``): a compact summary with the KPIs, the
budgets checked against the result and the flight path as an inline SVG."""

import html.parser
import re

import pandas as pd
import pytest

import pytest_flockai as fa
from pytest_flockai.budgets import check, evaluate


class Page(html.parser.HTMLParser):
    def __init__(self):
        super().__init__()
        self.cells, self.polylines, self.text = [], [], ""
        self._cell = None

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "td":
            self._cell = ""
        elif tag == "polyline":
            self.polylines.append(a)

    def handle_data(self, data):
        self.text += data
        if self._cell is not None:
            self._cell += data

    def handle_endtag(self, tag):
        if tag == "td" and self._cell is not None:
            self.cells.append(self._cell.strip())
            self._cell = None


def parse(text):
    p = Page()
    p.feed(text)
    return p


@pytest.fixture(scope="module")
def hover():
    return fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=1.0)).run()


def test_a_flight_shows_its_kpis_budgets_and_path(hover):
    assert "BROKEN" not in hover._repr_html_()            # no budget checked yet
    evaluate(hover, crashed="== 0", flight_time_s=">= 1 h")
    page = parse(hover._repr_html_())
    assert page.text.startswith("FlightResult: crazyflie-2-1, landed after ")
    cells = page.cells
    assert cells[cells.index("flight_time_s") + 1].endswith(" s")
    assert cells[cells.index("crashed") + 1] == "0"
    row = cells.index(">= 1 h")
    assert cells[row - 2:row] == ["BROKEN", "flight_time_s"]
    assert cells[cells.index("== 0") - 2] == "pass"
    (line,) = page.polylines
    assert len(line["points"].split()) >= 2
    assert "4.4 m across" in page.text                     # a hover: the 4 m minimum span
    with pytest.raises(AssertionError):
        check(hover, flight_time_s=">= 2 h")
    assert [v.budget for v in hover.verdicts] == [">= 2 h"]  # the last check is shown


def test_a_fleet_shows_one_colour_per_drone():
    pilots = [fa.pilots.Waypoints([(x, 0, 4), (x, 6, 4)], speed=4.0) for x in (0.0, 8.0)]
    r = fa.Fleet([fa.FleetDrone(f"d{i}", fa.drone("dji-mavic-2-pro"), p, pad=(8.0 * i, 0), seed=i)
                  for i, p in enumerate(pilots)]).run()
    page = parse(r._repr_html_())
    assert page.text.startswith("FleetResult: 2 drones, landed")
    assert "fleet.makespan_s" in page.cells and "d0" in " ".join(page.cells)
    assert len(page.polylines) == 2
    assert len({p["stroke"] for p in page.polylines}) == 2
    assert [re.sub(r"\s", "", t) for t in re.findall(r"<title>(.*?)</title>",
                                                     r._repr_html_())[:2]] == ["d0", "d1"]


def test_a_sweep_shows_its_axes_budgets_and_broken_variants():
    m = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=1.0))
    df = fa.sweep(m, payload_kg=[0.0, 0.005], budgets={"flight_time_s": ">= 5 s"}, workers=1)
    assert isinstance(df, pd.DataFrame) and len(df) == 2
    page = parse(df._repr_html_())
    assert page.text.startswith("sweep: 2 variant(s) over payload_kg (grid)")
    assert "budgets: flight_time_s >= 5 s; 2 broken" in page.text
    assert page.cells[0] == "0" and page.cells[1].endswith(" s") and "False" in page.cells
    derived = df[["payload_kg"]]
    assert type(derived) is pd.DataFrame                  # derived frames are plain again
