"""The dashboard's KPI table reads at 1280 px (a few headline columns, not one
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


def test_a_failing_hypothesis_tests_kept_flight_has_a_name_of_its_own(pytester):
    """Its kept (shrunk) example's flight is not named "flight", the name its first
    example's budget check row carries; the headline counts each budget of a test once."""
    pytester.makepyfile(test_h='''
import pytest
import pytest_flockai as fa
from hypothesis import given, settings, strategies as st, Phase

@settings(max_examples=6, deadline=None, derandomize=True, database=None,
          phases=[Phase.generate, Phase.shrink])
@given(d=st.floats(1.0, 4.0))
def test_fails(d):
    r = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=d)).run()
    fa.budgets.check(r, flight_time_s="<= 5 s")
''')
    res = pytester.runpytest_inprocess("-p", "no:cacheprovider", "--flockai-json", "r.json")
    res.assert_outcomes(failed=1)
    import json
    (t,) = json.loads((pytester.path / "r.json").read_text())["tests"]
    names = [f["name"] for f in t["flights"]]
    assert len(names) == 1 and names[0].startswith("flight-example-"), names
    rows = [b["flight"] for b in t["budgets"]]
    assert len(rows) == len(set(rows))                      # no two rows for one name
    assert names[0] in rows and not [b for b in t["budgets"]
                                     if b["flight"] == names[0] and b["verdict"] == "pass"]
    from pytest_flockai.reports import summary
    doc = json.loads((pytester.path / "r.json").read_text())
    assert "1 budget(s) broken" in summary.headline(doc)


def test_the_headline_counts_a_budget_broken_by_several_flights_of_a_test_once():
    from pytest_flockai.reports import summary
    row = {"kpi": "endurance_s", "budget": ">= 20 min", "verdict": "broken"}
    d = {"summary": {"failed": 2}, "tests": [
        {"nodeid": f"t.py::test_{k}", "outcome": "failed",
         "flights": [{"name": f"f{i}", "kpis": {}} for i in range(3)],
         "budgets": [{**row, "flight": f"f{i}"} for i in range(3)]} for k in "ab"]}
    assert "2 budget(s) broken" in summary.headline(d)
    assert 'data-card="budgets broken"><b>2</b>' in html.dashboard(d)


def test_policy_events_are_in_the_reports_without_artifacts(pytester):
    pytester.makepyfile(test_p='''
import pytest_flockai as fa

class Hold(fa.Policy):
    def start(self, run):
        self.held = False

    def decide(self, t, drone):
        if t >= 12.0 and not self.held:
            self.held = drone.hold()
            drone.mode("held")

def test_hold():
    fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=20.0),
               policies=[Hold(name="h", period_s=1.0)], until=16.0).run()
''')
    res = pytester.runpytest_inprocess("-p", "no:cacheprovider", "--flockai-json", "r.json",
                                       "--flockai-html", "d.html")
    res.assert_outcomes(passed=1)
    import json
    (t,) = json.loads((pytester.path / "r.json").read_text())["tests"]
    evs = t["flights"][0]["policy_events"]
    assert [e["kind"] for e in evs][:2] == ["policy", "policy_mode"]
    assert evs[0]["action"] == "hold" and evs[0]["t"] == 12.0
    page = (pytester.path / "d.html").read_text()
    assert "policies: flight: 12.0 s hold, 12.0 s held" in page
