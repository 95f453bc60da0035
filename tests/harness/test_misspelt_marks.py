"""A mark name close to one of the plugin's own (``flockia``, ``kpis``,
``flockai_sweeps``) is a collection error naming the mark and the one meant, instead
of an unknown mark that silently switches the gate off."""

from pathlib import Path

import pytest

HEADER = '''
import pytest
import pytest_flockai as fa
'''


def run(pytester, body, *args):
    pytester.makepyfile(test_marks=HEADER + body)
    return pytester.runpytest_inprocess("-p", "no:cacheprovider", *args)


@pytest.mark.parametrize("wrong, meant", [
    ('flockia(drone="crazyflie-2-1")', "flockai"),
    ('kpis(endurance_s=">= 50 min")', "kpi"),
    ('KPI(endurance_s=">= 50 min")', "kpi"),
    ('flockai_sweeps(seed=[0, 1])', "flockai_sweep"),
    ('flockaicache("off")', "flockai_cache"),
])
def test_a_misspelt_mark_is_a_collection_error_naming_what_was_meant(pytester, wrong, meant):
    res = run(pytester, f'''
@pytest.mark.{wrong}
def test_gate():
    pass

def test_other():
    pass
''')
    assert res.ret == pytest.ExitCode.INTERRUPTED         # collection errors stop the run
    res.assert_outcomes(errors=1)
    name = wrong.split("(")[0]
    res.stdout.fnmatch_lines(["*ERROR collecting test_marks.py*",
                              f"*test_gate: @pytest.mark.{name} is not a registered mark; "
                              f"did you mean @pytest.mark.{meant}?*"])


def test_a_misspelt_mark_on_a_class_or_module_is_found(pytester):
    res = run(pytester, '''
pytestmark = pytest.mark.kpis(flight_time_s=">= 1 s")

class TestA:
    def test_one(self):
        pass
''')
    res.assert_outcomes(errors=1)
    res.stdout.fnmatch_lines(["*test_one: @pytest.mark.kpis is not a registered mark*"])


def test_registered_and_unrelated_marks_are_left_alone(pytester):
    pytester.makeini('''
[pytest]
markers =
    kpis: the user's own mark of that name
''')
    res = run(pytester, '''
@pytest.mark.kpis
@pytest.mark.api
@pytest.mark.skipif(False, reason="no")
@pytest.mark.parametrize("x", [1, 2])
@pytest.mark.flockai(drone="crazyflie-2-1", pilot=fa.pilots.Hover(altitude=1.0, duration=0.5))
def test_fine(x, flight):
    pass
''', "-W", "ignore::pytest.PytestUnknownMarkWarning")
    res.assert_outcomes(passed=2)


def test_a_bad_budget_errors_at_setup_as_the_docs_say(pytester):
    """docs/how-to/pytest.md and reference/markers.md: a bad budget is an error of the
    test at setup (``--collect-only`` exits 0), not a collection error."""
    body = '''
@pytest.mark.kpi(flight_time_s=">= 3 parsecs")
def test_bad():
    pass
'''
    assert run(pytester, body, "--collect-only").ret == pytest.ExitCode.OK
    res = run(pytester, body)
    res.assert_outcomes(errors=1)
    res.stdout.fnmatch_lines(["*ERROR at setup of test_bad*"])
    docs = Path(__file__).resolve().parents[2] / "docs"
    for page in ("how-to/pytest.md", "reference/markers.md"):
        text = " ".join((docs / page).read_text().split())
        assert "at setup" in text and "--strict-markers" in text, page
