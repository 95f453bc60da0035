"""One naming rule for a test's flights, on every path: Mission(name=), else the
fixture that returned the flight, else "flight", "flight-2"... Regression: a
module-scoped fixture's flight was named after the Mission in the test that
flew it and after the fixture in later tests, so a test's flight names (and
its baseline entries) depended on which tests ran before it."""

import json

import pytest

from pytest_flockai.harness import markers

MODULE = """
import pytest
import pytest_flockai as fa

@pytest.fixture(scope="module")
def hover():
    return fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(1.0, 1.0), NAME).run()

@pytest.fixture(scope="module")
def unnamed():
    return fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(1.0, 1.0)).run()

def test_first(hover, unnamed):
    pass

def test_second(hover, unnamed):
    r = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(1.0, 0.5)).run()
"""


def _names(pytester, *args):
    res = pytester.runpytest_inprocess("-p", "no:cacheprovider", "--flockai-json=report.json", *args)
    res.assert_outcomes(passed=len([a for a in args if "::" in a]) or 2)
    doc = json.loads((pytester.path / "report.json").read_text())
    return {t["nodeid"].split("::")[-1]: [f["name"] for f in t["flights"]] for t in doc["tests"]}


@pytest.mark.parametrize("name", ["name='m1'", ""])
def test_flight_names_do_not_depend_on_test_order(pytester, name):
    pytester.makepyfile(test_flights=MODULE.replace(", NAME", f", {name}" if name else ""))
    full = _names(pytester)
    alone = _names(pytester, "test_flights.py::test_second")
    fixture_name = "m1" if name else "hover"
    assert full["test_first"] == [fixture_name, "unnamed"]
    assert full["test_second"] == [fixture_name, "unnamed", "flight"]
    assert alone["test_second"] == full["test_second"]


class _Item:
    def __init__(self, marks):
        self.nodeid = "t.py::test"
        self._marks = marks

    def iter_markers(self, name):
        return [m for m in self._marks if m.name == name]


def test_markers_parse_into_frozen_dataclasses():
    m = markers.parse(_Item([pytest.mark.kpi(flight_time_s=">= 1 min", flight="a").mark,
                             pytest.mark.flockai(max_regression={"energy_total_j": 2}).mark]))
    assert m.error is None
    (fb,) = m.budgets
    assert fb.flight == "a" and fb.budget.kpi == "flight_time_s" and fb.budget.limit == 60.0
    assert m.per_kpi_regression == {"energy_total_j": 2.0}
    with pytest.raises(AttributeError):
        m.error = "x"                                    # frozen
    bad = markers.parse(_Item([pytest.mark.flockai(droen="x").mark]))
    assert "unknown setting 'droen'" in bad.error and "did you mean" in bad.error.lower()
    bad = markers.parse(_Item([pytest.mark.kpi(flight_time_s=">= 3 apples").mark]))
    assert bad.error.startswith("pytest-flockai: bad @pytest.mark.kpi on t.py::test:")
