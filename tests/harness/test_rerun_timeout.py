"""Reruns start clean, timeouts are reported as timeouts, an overridden
fixture says that it wins over the marker, hypothesis examples are recorded
compactly. pytester runs generated tests that fly short Crazyflie hovers."""

import json

import pytest

HEADER = '''
import pytest
import pytest_flockai as fa


def fly(duration=2.0, name=None, seed=0, until="landed"):
    m = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=duration),
                   seed=seed, name=name, until=until)
    return m.run()
'''


def make(pytester, body):
    return pytester.makepyfile(test_runs=HEADER + body)


def report(pytester, name="r.json"):
    return {t["nodeid"].split("::")[-1]: t
            for t in json.loads((pytester.path / name).read_text())["tests"]}


def test_a_rerun_starts_clean(pytester):
    """The first attempt flies 2 s, the rerun 6 s against a >= 5 s budget: the rerun
    passes, with one flight named "flight" (before: the 2 s flight still broke it)."""
    pytest.importorskip("pytest_rerunfailures")
    make(pytester, '''
ATTEMPTS = []

@pytest.mark.kpi(flight_time_s=">= 5 s")
def test_flaky():
    ATTEMPTS.append(1)
    fly(duration=2.0 if len(ATTEMPTS) == 1 else 6.0)
''')
    res = pytester.runpytest_inprocess("-p", "no:cacheprovider", "--reruns", "1",
                                       "--flockai-json", "r.json")
    assert res.ret == 0 and res.parseoutcomes() == {"passed": 1, "rerun": 1}
    t = report(pytester)["test_flaky"]
    assert t["outcome"] == "passed"
    assert [f["name"] for f in t["flights"]] == ["flight"]
    assert [b["verdict"] for b in t["budgets"]] == ["pass"]


def test_a_timeout_is_reported_as_the_timeout(pytester):
    pytest.importorskip("pytest_timeout")
    make(pytester, '''
@pytest.mark.timeout(1, method="signal")
@pytest.mark.kpi(flight_time_s=">= 20 s")
def test_slow():
    fly(duration=3600.0)
''')
    res = pytester.runpytest_inprocess("-p", "no:cacheprovider", "--flockai-json", "r.json")
    res.assert_outcomes(failed=1)
    out = res.stdout.str()
    assert "Timeout" in out and "flew no mission" not in out
    t = report(pytester)["test_slow"]
    assert t["outcome"] == "failed" and t["error"] is None
    assert "Timeout" in t["message"]


def test_an_overridden_fixture_wins_over_the_marker_with_a_warning(pytester):
    make(pytester, '''
@pytest.fixture
def pilot():
    return fa.pilots.Hover(altitude=1.0, duration=1.0)

@pytest.fixture
def drone():
    return fa.drone("crazyflie-2-1")

@pytest.mark.flockai(pilot=fa.pilots.Hover(altitude=1.0, duration=5.0), seed=3)
def test_marker_pilot(flight):
    assert flight.kpis["flight_time_s"] < 4.0     # the fixture's 1 s hover flew
''')
    res = pytester.runpytest_inprocess("-p", "no:cacheprovider")
    res.assert_outcomes(passed=1, warnings=1)
    res.stdout.fnmatch_lines(["*@pytest.mark.flockai(pilot=...) on test_runs.py::"
                              "test_marker_pilot is ignored: the `pilot` fixture is overridden*"])
    assert "seed=...) on" not in res.stdout.str()       # `mission` is the plugin's: seed is read


@pytest.mark.slow
def test_hypothesis_examples_are_recorded_compactly(pytester):
    """12 examples x 2 flights: a passing test keeps counts and KPI ranges; a failing
    one keeps the shrunk example's flights in full, and one verdict per budget."""
    make(pytester, '''
from hypothesis import given, settings, strategies as st, Phase

SETTINGS = settings(max_examples=12, deadline=None, derandomize=True, database=None,
                    phases=[Phase.generate, Phase.shrink])

@SETTINGS
@given(d=st.floats(1.0, 4.0))
@pytest.mark.kpi(flight_time_s=">= 1 s")
def test_passes(d):
    fly(duration=d, name="a")
    fly(duration=1.0, name="b")

@SETTINGS
@given(d=st.floats(1.0, 4.0))
def test_fails(d):
    r = fly(duration=d, name="a")
    fly(duration=1.0, name="b")
    assert r.kpis["flight_time_s"] < 4.5
''')
    res = pytester.runpytest_inprocess("-p", "no:cacheprovider", "--flockai-json", "r.json",
                                       "--junitxml", "j.xml")
    res.assert_outcomes(passed=1, failed=1)
    tests = report(pytester)
    ok, bad = tests["test_passes"], tests["test_fails"]
    assert ok["hypothesis"]["examples"] == 12 and ok["hypothesis"]["flights"] == 24
    assert ok["flights"] == [] and len(ok["budgets"]) == 1 and ok["budgets"][0]["verdict"] == "pass"
    lo, hi = ok["hypothesis"]["kpi_ranges"]["flight_time_s"]
    assert 1.0 <= lo < hi
    # the shrunk example, in full, named apart from the earlier examples
    n = bad["flights"][0]["name"].rsplit("-", 1)[1]
    assert [f["name"] for f in bad["flights"]] == [f"a-example-{n}", f"b-example-{n}"]
    assert bad["hypothesis"]["kept"] == 2 and bad["hypothesis"]["examples"] > 2
    assert bad["flights"][0]["kpis"]["flight_time_s"] >= 4.5
    assert (pytester.path / "j.xml").stat().st_size < 20_000
    res.stdout.fnmatch_lines(["*hypothesis: 12 example(s), 24 flight(s)*"])
