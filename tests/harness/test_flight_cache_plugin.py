"""The flight cache in pytest (harness/flightcache.py): generated test files run
twice by pytester with pytest's cache directory; the second run reads the
flights back, reports say so, options and markers set the mode."""

import json

import pytest

BODY = '''
import pytest
import pytest_flockai as fa
from hypothesis import given, settings, strategies as st


def fly(seed=0):
    return fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=2.0),
                      seed=seed).run()


@pytest.mark.flockai(drone="crazyflie-2-1", pilot=fa.pilots.Hover(altitude=1.0, duration=2.0))
@pytest.mark.kpi(crashed="== 0")
def test_fixture_flight(flight):
    assert flight.kpis["flight_time_s"] > 0


def test_body_flight():
    assert fly(seed=3).kpis["crashed"] == 0
'''

HYPOTHESIS = '''
@settings(max_examples=2, deadline=None, database=None, derandomize=True)
@given(seed=st.integers(0, 1))
def test_searched(seed):
    fly(seed=seed)


@pytest.mark.flockai_cache("readwrite")
@settings(max_examples=2, deadline=None, database=None, derandomize=True)
@given(seed=st.integers(0, 1))
def test_searched_and_cached(seed):
    fly(seed=seed + 10)
'''


def statuses(path):
    doc = json.loads(path.read_text())
    return {t["nodeid"].split("::")[-1]: [(f.get("cache") or {}).get("status") for f in t["flights"]]
            for t in doc["tests"]}


def test_the_second_run_reads_the_flights_back(pytester):
    pytester.makepyfile(test_cached=BODY)
    out = pytester.path / "r.json"
    first = pytester.runpytest_inprocess("--flockai-json", str(out))
    first.assert_outcomes(passed=2)
    first.stdout.fnmatch_lines(["flockai cache: 2 flown and stored"])
    assert statuses(out) == {"test_fixture_flight": ["stored"], "test_body_flight": ["stored"]}
    assert list((pytester.path / ".pytest_cache" / "d" / "flockai-flights").glob("*/*.flight"))
    second = pytester.runpytest_inprocess("--flockai-json", str(out))
    second.assert_outcomes(passed=2)
    second.stdout.fnmatch_lines(["flockai cache: 2 from the cache", "*flight (cached): *"])
    assert statuses(out) == {"test_fixture_flight": ["hit"], "test_body_flight": ["hit"]}


def test_cache_off_clear_and_read(pytester):
    pytester.makepyfile(test_cached=BODY)
    out = pytester.path / "r.json"
    pytester.runpytest_inprocess("--flockai-cache=off", "--flockai-json", str(out))
    assert statuses(out) == {"test_fixture_flight": [None], "test_body_flight": [None]}
    pytester.runpytest_inprocess("--flockai-cache=read", "--flockai-json", str(out))
    assert statuses(out) == {"test_fixture_flight": ["flown"], "test_body_flight": ["flown"]}
    pytester.runpytest_inprocess()
    pytester.runpytest_inprocess("--flockai-cache-clear", "--flockai-json", str(out))
    assert statuses(out) == {"test_fixture_flight": ["stored"], "test_body_flight": ["stored"]}
    res = pytester.runpytest_inprocess("--flockai-cache=sometimes")
    assert res.ret == pytest.ExitCode.USAGE_ERROR


def test_hypothesis_tests_are_not_cached_unless_marked(pytester):
    pytester.makepyfile(test_cached=BODY + HYPOTHESIS)
    out = pytester.path / "r.json"
    pytester.runpytest_inprocess("--flockai-json", str(out)).assert_outcomes(passed=4)
    # hypothesis examples are recorded compactly (no per-flight rows): count the entries
    # stored: the two plain tests' flights and the marked search's two seeds, not the other's
    stored = list((pytester.path / ".pytest_cache" / "d" / "flockai-flights").glob("*/*.flight"))
    assert len(stored) == 4


def test_off_without_the_cacheprovider(pytester):
    pytester.makepyfile(test_cached=BODY)
    res = pytester.runpytest_inprocess("-p", "no:cacheprovider")
    res.assert_outcomes(passed=2)
    res.stdout.fnmatch_lines(["flockai cache: off (pytest's cacheprovider is disabled*"])


def test_an_unwritable_cache_dir_warns_once_and_the_run_goes_on(pytester):
    pytester.makepyfile(test_cached=BODY)
    (pytester.path / "blocker").write_text("a file, not a directory")
    res = pytester.runpytest_inprocess("-o", "cache_dir=blocker/cache", "-W",
                                       "always::UserWarning")
    res.assert_outcomes(passed=2)
    text = res.stdout.str()
    assert text.count("the flight cache cannot be written") == 1
    res.stdout.fnmatch_lines(["flockai cache: 2 flown, not stored"])


@pytest.mark.slow
def test_xdist_workers_share_the_cache(pytester):
    pytest.importorskip("xdist")
    pytester.makepyfile(test_cached=BODY)
    out = pytester.path / "r.json"
    pytester.runpytest_subprocess("-n", "2", "--flockai-json", str(out)).assert_outcomes(passed=2)
    assert statuses(out) == {"test_fixture_flight": ["stored"], "test_body_flight": ["stored"]}
    res = pytester.runpytest_subprocess("-n", "2", "--flockai-json", str(out))
    res.assert_outcomes(passed=2)
    assert statuses(out) == {"test_fixture_flight": ["hit"], "test_body_flight": ["hit"]}
    res.stdout.fnmatch_lines(["flockai cache: 2 from the cache"])


def test_a_bad_cache_marker_fails_that_test_only(pytester):
    pytester.makepyfile(test_cached=BODY + '''

@pytest.mark.flockai_cache("sometimes")
def test_bad_marker():
    fly()
''')
    res = pytester.runpytest_inprocess("-p", "no:randomly")
    res.assert_outcomes(passed=2, errors=1)
    res.stdout.fnmatch_lines(["*flockai_cache('sometimes') is not allowed; allowed: off, read, "
                              "write, readwrite*"])


def test_a_shared_flight_is_counted_once(pytester):
    pytester.makepyfile(test_cached='''
import pytest
import pytest_flockai as fa


@pytest.fixture(scope="session")
def shared():
    return fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=2.0)).run()


def test_one(shared):
    pass


def test_two(shared):
    pass
''')
    res = pytester.runpytest_inprocess()
    res.assert_outcomes(passed=2)
    res.stdout.fnmatch_lines(["flockai cache: 1 flown and stored"])


SHARED = '''
import pytest
import pytest_flockai as fa


@pytest.fixture(scope="module")
def hover():
    return fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=2.0)).run()


def test_one(hover):
    assert hover.kpis["crashed"] == 0


def test_two(hover):
    assert hover.kpis["flight_time_s"] > 0
'''


def test_terminal_headline_and_dashboard_count_a_shared_flight_once(pytester):
    pytester.makepyfile(test_shared=SHARED)
    args = ("--flockai-json", "r.json", "--flockai-html", "d.html", "--flockai-md", "s.md")
    pytester.runpytest_inprocess(*args).assert_outcomes(passed=2)
    res = pytester.runpytest_inprocess(*args)
    res.assert_outcomes(passed=2)
    doc = json.loads((pytester.path / "r.json").read_text())
    listed = [f for t in doc["tests"] for f in t["flights"]]
    assert len(listed) == 2 and {f["cache"]["status"] for f in listed} == {"hit"}
    res.stdout.fnmatch_lines(["flockai cache: 1 from the cache"])
    md = (pytester.path / "s.md").read_text()
    assert "2 test(s) (2 passed), 1 flight(s)" in md and "1 flight(s) from the cache" in md
    html = (pytester.path / "d.html").read_text()
    assert '<b>1</b>flights<small>1 from the cache; 2 listed by the tests</small>' in html
