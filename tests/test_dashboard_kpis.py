"""Issue 35: the dashboard's KPI table reads at 1280 px (a few headline columns, not one
per KPI of the run: 67,868 px before), every KPI is still shown, one row each, and a
fleet flight's headline cells carry its drones' numbers instead of n/a."""

import re

from pytest_flockai.reports import html


def doc():
    many = {f"task{i}.latency_p{q}_s": 0.01 * i + q for i in range(20) for q in (50, 95)}
    single = {"flight_time_s": 120.0, "energy_total_j": 5000.0, "crashed": 0.0, **many}
    fleet = {"d1.flight_time_s": 100.0, "d2.flight_time_s": 140.0, "fleet.makespan_s": 140.0,
             "d1.energy_total_j": 4000.0, "d2.energy_total_j": 4500.0}
    return {"schema": "pytest-flockai/1", "summary": {"passed": 2}, "tests": [
        {"nodeid": "t.py::test_one", "outcome": "passed", "flights": [
            {"name": "flight", "kpis": single}]},
        {"nodeid": "t.py::test_fleet", "outcome": "passed", "flights": [
            {"name": "fleet", "kpis": fleet}]}]}


def headers(page: str, tid: str) -> list[str]:
    start = page.index(f'id="{tid}"')
    head = page[start:page.index("</thead>", start)]
    return re.findall(r"<th(?:\s[^>]*)?>(.*?)</th>", head)


def test_the_kpi_table_has_a_few_columns_and_every_kpi_has_a_row():
    page = html.dashboard(doc())
    cols = headers(page, "kpis")
    assert len(cols) <= 4 + html.KPI_COLUMNS
    assert cols[4:7] == ["flight_time_s", "energy_total_j", "crashed"]
    every = page[page.index('id="every-kpi"'):]
    assert headers(page, "every-kpi") == ["outcome", "test", "flight", "group", "KPI", "value"]
    for kpi in list(doc()["tests"][0]["flights"][0]["kpis"]) + ["d2.flight_time_s",
                                                                "fleet.makespan_s"]:
        assert f">{kpi}</td>" in every, kpi
    assert "more KPI(s) per flight in Every KPI" in page


def test_a_fleet_flights_headline_cells_show_its_drones():
    page = html.dashboard(doc())
    table = page[page.index('id="kpis"'):page.index("</table>", page.index('id="kpis"'))]
    fleet_row = table[table.index("test_fleet"):]
    fleet_row = fleet_row[:fleet_row.index("</tr>")]
    assert "(2 drones)" in fleet_row and "n/a" not in fleet_row.split("flown", 1)[1].split(
        "</td>")[1]


def test_the_dashboard_says_why_pictures_are_missing_without_matplotlib(pytester):
    pytester.makeconftest('''
import sys
sys.modules["matplotlib"] = None          # as if matplotlib were not installed
''')
    pytester.makepyfile(test_fly='''
import pytest
import pytest_flockai as fa

@pytest.mark.flockai(drone="crazyflie-2-1", pilot=fa.pilots.Hover(altitude=1.0, duration=0.5))
def test_hover(flight):
    pass
''')
    res = pytester.runpytest_subprocess("-p", "no:cacheprovider", "--flockai-html", "d.html")
    res.assert_outcomes(passed=1)
    page = (pytester.path / "d.html").read_text()
    assert 'id="pictures-missing"' in page and "matplotlib is not installed" in page
    assert "data:image/png" not in page


def test_the_note_is_absent_when_pictures_are_drawn():
    assert 'id="pictures-missing"' not in html.dashboard(doc())
