"""The pytest layer, end to end: generated test files run by pytester, real flights.

Every generated test flies a Crazyflie hovering 1 m up for a couple of
simulated seconds (well under a second of wall time per flight).
"""

import json
import sys
import xml.etree.ElementTree as ET

import pytest

HEADER = '''
import pytest
import pytest_flockai as fa


def cf(duration=2.0, **kw):
    """Quick settings: a short Crazyflie hover."""
    return pytest.mark.flockai(drone="crazyflie-2-1",
                               pilot=fa.pilots.Hover(altitude=1.0, duration=duration), **kw)


def fly(duration=2.0, name=None, seed=0):
    m = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=duration),
                   seed=seed, name=name)
    return m.run()
'''


def make(pytester, body, name="test_flights"):
    return pytester.makepyfile(**{name: HEADER + body})


def run(pytester, *args):
    return pytester.runpytest_inprocess("-p", "no:cacheprovider", *args)


def load(path):
    return json.loads(path.read_text())


def by_nodeid(report):
    return {t["nodeid"].split("::")[-1]: t for t in report["tests"]}


# -- budgets ------------------------------------------------------------------------------
def test_passing_and_broken_budgets(pytester):
    make(pytester, '''
@cf()
@pytest.mark.kpi(flight_time_s=">= 2 s", energy_share_proc="< 50%", crashed="== 0",
                 energy_total_j="<= 2 Wh", max_speed_mps="<= 20 km/h")
def test_within_budget(flight):
    assert flight.kpis["crashed"] == 0

@cf()
@pytest.mark.kpi(flight_time_s=">= 24 min", crashed="== 0")
def test_too_short(flight):
    pass
''')
    res = run(pytester)
    res.assert_outcomes(passed=1, failed=1)
    out = res.stdout.str()
    res.stdout.fnmatch_lines([
        "*1 of 2 KPI budget(s) broken in test_flights.py::test_too_short*",
        "*flight*KPI*budget*actual*margin*verdict*",
        "*flight*flight_time_s*>= 24 min*min*-2?.* min*BROKEN*",
        "*flight*crashed*== 0*0*0*ok*",
    ])
    assert "test_within_budget" not in out.split("= FAILURES =")[1].split("flockai KPIs")[0]


def test_bad_markers_error_at_setup_before_anything_flies(pytester):
    make(pytester, '''
@cf()
@pytest.mark.kpi(flight_tme_s=">= 24 min")
def test_unknown_kpi(flight):
    pass

@cf()
@pytest.mark.kpi(flight_time_s="=> 24 min")
def test_bad_operator(flight):
    pass

@cf()
@pytest.mark.kpi(flight_time_s=">= 24 minutes")
def test_bad_unit(flight):
    pass

@cf()
@pytest.mark.kpi(flight_time_s=">= 5 m")
def test_wrong_dimension(flight):
    pass

@pytest.mark.flockai(drones="crazyflie-2-1")
def test_bad_setting(flight):
    pass

@cf()
def test_fine(flight):
    pass
''')
    res = run(pytester, "--flockai-json", "report.json")
    res.assert_outcomes(passed=1, errors=5)
    res.stdout.fnmatch_lines([
        "*ERROR at setup of test_unknown_kpi*",
        "*bad @pytest.mark.kpi on test_flights.py::test_unknown_kpi: unknown KPI 'flight_tme_s'"
        " (did you mean: flight_time_s*",
        "*ERROR at setup of test_bad_operator*",
        "*KPI flight_time_s: budget '=> 24 min': '=>' is not allowed; allowed operators: "
        "<, <=, >, >=, ==*",
        "*ERROR at setup of test_bad_unit*",
        "*KPI flight_time_s: budget '>= 24 minutes': unknown unit 'minutes'*allowed for "
        "flight_time_s: s, ms, min, h*",
        "*ERROR at setup of test_wrong_dimension*",
        "*unit 'm' measures length, but flight_time_s is in 's' (time)*",
        "*ERROR at setup of test_bad_setting*",
        "*bad @pytest.mark.flockai*unknown setting 'drones' (did you mean: drone*",
    ])
    assert "Traceback" not in res.stdout.str()
    tests = by_nodeid(load(pytester.path / "report.json"))
    for name in ("test_unknown_kpi", "test_bad_operator", "test_bad_unit", "test_wrong_dimension"):
        assert tests[name]["outcome"] == "error"
        assert tests[name]["flights"] == []          # the flight fixture never ran
        assert "bad @pytest.mark.kpi" in tests[name]["error"]
    assert len(tests["test_fine"]["flights"]) == 1


def test_several_flights_per_test(pytester):
    make(pytester, '''
@pytest.mark.kpi(crashed="== 0")
@pytest.mark.kpi(flight_time_s=">= 6 s", flight="long")
def test_named_budget():
    fly(duration=1.0, name="short")
    fly(duration=5.0, name="long")

@pytest.mark.kpi(flight_time_s=">= 6 s")
def test_every_flight_checked():
    fly(duration=5.0)
    fly(duration=1.0)

@cf()
@pytest.mark.kpi(crashed="== 0")
def test_fixture_and_body(flight):
    again = fly(duration=1.0)
    assert flight is not again
''')
    res = run(pytester, "--flockai-json", "report.json")
    res.assert_outcomes(passed=2, failed=1)
    res.stdout.fnmatch_lines([
        "*1 of 2 KPI budget(s) broken in test_flights.py::test_every_flight_checked*",
        "*flight  *flight_time_s*>= 6 s*ok*",
        "*flight-2*flight_time_s*>= 6 s*BROKEN*",
    ])
    tests = by_nodeid(load(pytester.path / "report.json"))
    named = tests["test_named_budget"]
    assert [f["name"] for f in named["flights"]] == ["short", "long"]
    assert sorted((b["flight"], b["kpi"]) for b in named["budgets"]) == [
        ("long", "crashed"), ("long", "flight_time_s"), ("short", "crashed")]
    assert [f["name"] for f in tests["test_every_flight_checked"]["flights"]] == ["flight",
                                                                                  "flight-2"]
    fb = tests["test_fixture_and_body"]["flights"]
    assert [f["name"] for f in fb] == ["flight", "flight-2"]
    assert fb[0]["kpis"]["flight_time_s"] > fb[1]["kpis"]["flight_time_s"]


def test_marker_misuse_found_after_the_body(pytester):
    make(pytester, '''
@pytest.mark.kpi(flight_time_s=">= 1 s")
def test_flew_nothing():
    pass

@pytest.mark.kpi(flight_time_s=">= 1 s", flight="lond")
def test_no_such_flight():
    fly(name="long")

@cf()
@pytest.mark.kpi(inference_count=">= 1")
def test_kpi_not_produced(flight):
    pass
''')
    res = run(pytester)
    res.assert_outcomes(failed=3)
    res.stdout.fnmatch_lines([
        "*test_flights.py::test_flew_nothing has @pytest.mark.kpi budgets (flight_time_s) but "
        "flew no mission*",
        "*@pytest.mark.kpi(flight='lond') on test_flights.py::test_no_such_flight: no flight "
        "named 'lond' (did you mean: long?); this test flew: long*",
        "*budget inference_count '>= 1': flight 'flight' did not produce KPI "
        "'inference_count'*it produced: flight_time_s*",
    ])


# -- reports ----------------------------------------------------------------------------------
def test_json_report_is_written_when_tests_fail(pytester):
    make(pytester, '''
@cf()
@pytest.mark.kpi(flight_time_s=">= 24 min")
def test_broken(flight):
    pass

@cf(seed=3)
def test_plain(flight):
    pass

def test_no_flight():
    pass
''')
    (pytester.path / "out").mkdir()
    res = run(pytester, "--flockai-json", "out/report.json")
    res.assert_outcomes(passed=2, failed=1)
    report = load(pytester.path / "out" / "report.json")
    assert report["schema"] == "pytest-flockai/1"
    assert report["interrupted"] is False
    env = report["environment"]
    assert env["python"] == "{}.{}.{}".format(*sys.version_info[:3])
    assert env["platform"]
    assert {"pytest-flockai", "pytest", "mujoco", "numpy"} <= set(env["packages"])
    assert env["packages"]["pytest"] == pytest.__version__
    tests = by_nodeid(report)
    assert set(tests) == {"test_broken", "test_plain", "test_no_flight"}   # every test
    assert tests["test_no_flight"]["flights"] == [] and tests["test_no_flight"]["outcome"] == "passed"
    assert report["summary"] == {"tests": 3, "passed": 2, "failed": 1, "flights": 2}
    broken = tests["test_broken"]
    assert broken["outcome"] == "failed"
    assert broken["nodeid"] == "test_flights.py::test_broken"
    (b,) = broken["budgets"]
    assert (b["kpi"], b["budget"], b["limit"], b["verdict"], b["flight"]) == (
        "flight_time_s", ">= 24 min", 1440.0, "fail", "flight")
    assert b["actual"] == broken["flights"][0]["kpis"]["flight_time_s"]
    assert b["margin"] == pytest.approx(b["actual"] - 1440.0)
    (f,) = tests["test_plain"]["flights"]
    assert f["name"] == "flight"
    assert f["scenario"]["seed"] == 3
    assert f["scenario"]["drone"]["name"] == "crazyflie-2-1"
    assert f["kpis"]["crashed"] == 0.0 and f["kpis"]["flight_time_s"] > 2.0
    assert tests["test_plain"]["budgets"] == []
    assert not list((pytester.path / "out").glob(".*"))      # no temporary file left


def test_json_report_is_written_when_the_session_is_interrupted(pytester):
    make(pytester, '''
@cf()
def test_first(flight):
    pass

def test_interrupt():
    raise KeyboardInterrupt

def test_never_run():
    pass
''')
    res = pytester.runpytest_inprocess("-p", "no:cacheprovider", "--flockai-json", "report.json",
                                       no_reraise_ctrlc=True)
    assert res.ret == pytest.ExitCode.INTERRUPTED
    report = load(pytester.path / "report.json")
    assert report["interrupted"] is True
    # the test cut off is listed as interrupted, the one never started is not
    assert {t["nodeid"]: t["outcome"] for t in report["tests"]} == {
        "test_flights.py::test_first": "passed", "test_flights.py::test_interrupt": "interrupted"}
    assert report["tests"][0]["flights"][0]["kpis"]["flight_time_s"] > 0


@pytest.mark.parametrize("option, value, message", [
    ("--flockai-json", "missing-dir/report.json", "directory * does not exist"),
    ("--flockai-json", ".", "is a directory; give a file path"),
    ("--flockai-save", "missing-dir/base.json", "directory * does not exist"),
    ("--flockai-baseline", "missing.json", "baseline file * does not exist*"),
    ("--flockai-baseline", "corrupt.json", "baseline file * is not valid JSON*"),
    ("--flockai-max-regression", "lots", "--flockai-max-regression = 'lots' is not allowed*"),
])
def test_bad_options_are_usage_errors_before_any_flight(pytester, option, value, message):
    make(pytester, '''
def test_flies():
    fly()
    open("flew.txt", "w").close()
''')
    (pytester.path / "corrupt.json").write_text("{not json")
    res = run(pytester, option, value)
    assert res.ret == pytest.ExitCode.USAGE_ERROR
    res.stderr.fnmatch_lines([f"ERROR: *{message}"])
    assert not (pytester.path / "flew.txt").exists()


def test_junit_properties(pytester):
    make(pytester, '''
@cf()
def test_one(flight):
    pass

def test_two():
    fly(name="a")
    fly(name="b", duration=1.0)

def test_none():
    pass
''')
    res = run(pytester, "--junitxml", "junit.xml", "--flockai-json", "report.json")
    res.assert_outcomes(passed=3)
    root = ET.parse(pytester.path / "junit.xml").getroot()
    # the schema allows no properties in a testcase: suite properties per test
    assert not [p for tc in root.iter("testcase") for p in tc.iter("property")]
    suite = {p.get("name"): p.get("value") for p in root.find("testsuite").iter("property")}
    props = {n: {k.split("].", 1)[1]: v for k, v in suite.items()
                 if k.startswith(f"flockai[test_flights.py::{n}]")}
             for n in ("test_one", "test_two", "test_none")}
    tests = by_nodeid(load(pytester.path / "report.json"))
    kpis = tests["test_one"]["flights"][0]["kpis"]
    assert set(props["test_one"]) == set(kpis)
    assert float(props["test_one"]["flight_time_s"]) == kpis["flight_time_s"]
    assert props["test_two"]["a.flight_time_s"]
    assert props["test_two"]["b.energy_total_j"]
    assert "flight_time_s" not in props["test_two"]
    assert props["test_none"] == {}


def test_terminal_summary_compact_and_verbose(pytester):
    make(pytester, '''
@cf()
@pytest.mark.kpi(distance_m="<= 10 m")
def test_hover(flight):
    pass
''')
    res = run(pytester)
    res.stdout.fnmatch_lines(["*= flockai KPIs =*", "test_flights.py::test_hover (passed)",
                              "  flight: flight_time_s=* s  energy_total_j=* J*distance_m=* m"])
    assert "endurance_s" not in res.stdout.str()
    res = run(pytester, "-v")
    res.stdout.fnmatch_lines(["*= flockai KPIs =*", "*flight 'flight': landed, drone crazyflie-2-1",
                              "*KPI*value*better*", "*endurance_s*s*higher*",
                              "*distance_m*<= 10 m*ok*"])


# -- baselines ---------------------------------------------------------------------------------------------
def test_baseline_fails_only_the_regressed_test(pytester):
    make(pytester, '''
@cf()
def test_steady(flight):
    pass

@cf()
def test_regressed(flight):
    pass

@cf()
def test_new(flight):
    pass
''')
    res = run(pytester, "--flockai-save", "base.json")
    res.assert_outcomes(passed=3)
    base = load(pytester.path / "base.json")
    assert base["schema"] == "pytest-flockai-baseline/1"
    nodeid = "test_flights.py::test_regressed"
    assert set(base["tests"]) == {"test_flights.py::test_steady", nodeid,
                                  "test_flights.py::test_new"}
    energy = base["tests"][nodeid]["flight"]["energy_total_j"]
    # the baseline says this test used to need 20% less energy and fly 20% longer
    base["tests"][nodeid]["flight"]["energy_total_j"] = energy * 0.8
    base["tests"][nodeid]["flight"]["endurance_s"] *= 1.2
    # a 3% worse energy is within the default 5%; KPIs without a better direction are ignored
    base["tests"]["test_flights.py::test_steady"]["flight"]["energy_total_j"] *= 0.97
    base["tests"]["test_flights.py::test_steady"]["flight"]["distance_m"] *= 0.5
    del base["tests"]["test_flights.py::test_new"]
    (pytester.path / "base.json").write_text(json.dumps(base))

    res = run(pytester, "--flockai-baseline", "base.json", "--flockai-json", "r.json")
    res.assert_outcomes(passed=2, failed=1)
    res.stdout.fnmatch_lines([
        "*2 KPI regression(s) against baseline *base.json (max 5%) in "
        "test_flights.py::test_regressed:",
        "*flight*KPI*baseline*actual*change*better*",
        "*flight*energy_total_j*J*J*+25.00%*lower*",
        "*flight*endurance_s*s*s*-16.67%*higher*",
        "FAILED test_flights.py::test_regressed*",
    ])
    tests = by_nodeid(load(pytester.path / "r.json"))
    assert [r["kpi"] for r in tests["test_regressed"]["regressions"]] == ["energy_total_j",
                                                                          "endurance_s"]
    assert tests["test_steady"]["regressions"] == []

    res = run(pytester, "--flockai-baseline", "base.json", "--flockai-max-regression", "30")
    res.assert_outcomes(passed=3)


# -- fixtures, markers, hooks, ini ----------------------------------------------------------------------
def test_fixture_defaults_and_quick_settings(pytester):
    make(pytester, '''
def test_defaults(drone, world, pilot, tasks, probes, mission):
    assert drone.name == "dji-mavic-2-pro"
    assert world is None and tasks == () and probes is None
    assert isinstance(pilot, fa.pilots.Hover)
    assert (pilot.altitude, pilot.duration) == (10.0, 30.0)
    assert isinstance(mission, fa.Mission)
    assert (mission.drone, mission.pilot, mission.seed, mission.until) == (drone, pilot, 0, "landed")

@cf(seed=7, until=3.0, wind=(1.0, 0.0, 0.0), name="gusty")
def test_settings(mission, drone):
    assert drone.name == "crazyflie-2-1"
    assert (mission.seed, mission.until, mission.name) == (7, 3.0, "gusty")
    assert mission.wind.mean == (1.0, 0.0, 0.0) or list(mission.wind.mean) == [1.0, 0.0, 0.0]

@pytest.mark.flockai(seed=1)
class TestClassMarker:
    @pytest.mark.flockai(seed=2)
    def test_closest_wins(self, mission):
        assert mission.seed == 2

    def test_class(self, mission):
        assert mission.seed == 1

class TestOverride:
    @pytest.fixture
    def pilot(self):
        return fa.pilots.Hover(altitude=1.0, duration=1.0)

    @pytest.mark.flockai(drone="crazyflie-2-1")
    def test_override_fixture(self, flight):
        assert flight.scenario["pilot"]["duration"] == 1.0
''')
    res = run(pytester, "--flockai-json", "report.json")
    res.assert_outcomes(passed=5)
    tests = by_nodeid(load(pytester.path / "report.json"))
    flown = [name for name, t in tests.items() if t["flights"]]
    assert flown == ["test_override_fixture"]    # building a mission flies nothing
    assert len(tests) == 5                       # every test is in the report


def test_hooks_adjust_mission_and_derived_kpis(pytester):
    pytester.makeconftest('''
def pytest_flockai_adjust_mission(mission, item):
    if item.get_closest_marker("slow_seed"):
        return mission.replace(seed=42)

def pytest_flockai_derived_kpis(result, item):
    k = result.kpis
    return {"probe.hover_share": k["hover_time_s"] / k["flight_time_s"]}

def pytest_flockai_json_report(report, config):
    report["ci"] = {"build": 7}
''')
    pytester.makeini("[pytest]\nmarkers = slow_seed\n")
    make(pytester, '''
@cf()
@pytest.mark.slow_seed
@pytest.mark.kpi({"probe.hover_share": "> 10%"})
def test_derived(flight):
    assert flight.scenario["seed"] == 42
    assert 0 < flight.kpis["probe.hover_share"] < 1

@cf()
@pytest.mark.kpi({"probe.hover_share": "> 99%"})
def test_derived_broken(flight):
    pass
''')
    res = run(pytester, "--flockai-json", "report.json")
    res.assert_outcomes(passed=1, failed=1)
    res.stdout.fnmatch_lines(["*probe.hover_share*> 99%*BROKEN*"])
    report = load(pytester.path / "report.json")
    assert report["ci"] == {"build": 7}
    assert "probe.hover_share" in by_nodeid(report)["test_derived"]["flights"][0]["kpis"]


def test_adjust_hooks_chain_and_old_in_place_hooks_warn(pytester):
    """Two hooks: the second sees the first's spec; an old hook that assigns in place
    still works with a DeprecationWarning, and its bad value is a ConfigError naming it."""
    pytester.makeconftest('''
import pytest

@pytest.hookimpl(tryfirst=True)
def pytest_flockai_adjust_mission(mission, item):
    return mission.replace(until=0.5)
''')
    pytester.makepyfile(old_hooks='''
def pytest_flockai_adjust_mission(mission, item):
    if item.get_closest_marker("bad_seed"):
        mission.seed = -1
    else:
        mission.seed = mission.seed + 7 if mission.until == 0.5 else 0
''')
    pytester.makeini("[pytest]\nmarkers = bad_seed\n")
    make(pytester, '''
@cf()
def test_chained(mission):
    assert (mission.until, mission.seed) == (0.5, 7)

@cf()
@pytest.mark.bad_seed
def test_bad(mission):
    pass
''')
    pytester.syspathinsert()
    res = run(pytester, "-p", "old_hooks")
    res.assert_outcomes(passed=1, errors=1)
    res.stdout.fnmatch_lines(["*ConfigError: Mission: seed = -1 is not allowed*",
                              "*DeprecationWarning: pytest_flockai_adjust_mission in *assigning "
                              "mission fields in place (seed) is deprecated*"], consecutive=False)


def test_ini_options(pytester):
    pytester.makeini("[pytest]\nflockai_json = reports/flockai.json\n"
                     "flockai_save = base.json\nflockai_max_regression = 2.5\n")
    (pytester.path / "reports").mkdir()
    make(pytester, '''
@cf()
def test_hover(flight):
    pass
''')
    res = run(pytester)
    res.assert_outcomes(passed=1)
    report = load(pytester.path / "reports" / "flockai.json")
    assert report["options"]["max_regression_pct"] == 2.5
    assert (pytester.path / "base.json").exists()
    # the command line wins over the ini file
    res = run(pytester, "--flockai-json", "cli.json")
    assert (pytester.path / "cli.json").exists()
    res = run(pytester, "--help")
    res.stdout.fnmatch_lines(["*--flockai-json=PATH*", "*--flockai-artifacts=DIR*",
                              "*flockai_max_regression*"])


def test_artifacts(pytester):
    make(pytester, '''
@cf()
def test_hover(flight):
    pass
''')
    res = run(pytester, "--flockai-artifacts", "art")
    res.assert_outcomes(passed=1)
    folder, = (pytester.path / "art").glob("test_flights.py_test_hover-*")   # + hash of the id
    assert (folder / "flight.telemetry.csv").read_text().startswith("t,x,y,z")
    assert load(folder / "flight.json")["kpis"]["flight_time_s"] > 0


# -- xdist ---------------------------------------------------------------------------------------------------
@pytest.mark.slow
def test_xdist_reports_equal_the_serial_ones(pytester):
    pytest.importorskip("xdist")
    make(pytester, "".join(f'''
@cf(seed={i}, duration={1.0 + i % 3})
@pytest.mark.kpi(crashed="== 0")
def test_hover_{i}(flight):
    fly(duration=1.0, name="extra", seed={i})
''' for i in range(6)))
    # both in fresh processes: each imports the same core, like CI would
    serial = pytester.runpytest_subprocess("-p", "no:cacheprovider", "--flockai-json",
                                           "serial.json", "--junitxml", "serial.xml")
    serial.assert_outcomes(passed=6)
    par = pytester.runpytest_subprocess("-p", "no:cacheprovider", "-n", "2", "--flockai-json",
                                        "parallel.json", "--junitxml", "parallel.xml")
    par.assert_outcomes(passed=6)
    par.stdout.fnmatch_lines(["*2 workers*", "*= flockai KPIs =*"])

    def kpis(path):
        return {t["nodeid"]: {f["name"]: f["kpis"] for f in t["flights"]}
                for t in load(path)["tests"]}

    a, b = kpis(pytester.path / "serial.json"), kpis(pytester.path / "parallel.json")
    assert len(a) == 6 and all(set(v) == {"flight", "extra"} for v in a.values())
    assert a == b

    def props(path):
        return {p.get("name"): p.get("value")
                for p in ET.parse(path).getroot().find("testsuite").iter("property")}

    pa, pb = props(pytester.path / "serial.xml"), props(pytester.path / "parallel.xml")
    assert pa == pb and pa["flockai[test_flights.py::test_hover_0].extra.crashed"] == "0.0"


def test_shared_flight_fixture_counts_for_every_test_using_it(pytester):
    make(pytester, '''
@pytest.fixture(scope="module")
def survey():
    return fly(duration=3.0, name="survey")

@pytest.mark.kpi(flight_time_s=">= 3 s")
def test_first(survey):
    pass

@pytest.mark.kpi(flight_time_s=">= 24 min")
def test_second(survey):
    pass
''')
    res = run(pytester, "--flockai-json", "report.json")
    res.assert_outcomes(passed=1, failed=1)
    tests = by_nodeid(load(pytester.path / "report.json"))
    # flown during test_first's setup (named by the mission), adopted by test_second
    assert [f["name"] for f in tests["test_first"]["flights"]] == ["survey"]
    assert [f["name"] for f in tests["test_second"]["flights"]] == ["survey"]
    assert tests["test_first"]["flights"][0]["kpis"] == tests["test_second"]["flights"][0]["kpis"]
    assert tests["test_second"]["budgets"][0]["verdict"] == "fail"


def test_help_works_with_bad_options_in_the_ini_file(pytester):
    pytester.makeini("[pytest]\nflockai_json = missing/report.json\n"
                     "flockai_baseline = missing.json\nflockai_max_regression = -1\n")
    res = run(pytester, "--help")
    assert res.ret == 0
    res.stdout.fnmatch_lines(["*pytest-flockai*", "*--flockai-baseline=PATH*"])
    res = run(pytester)
    assert res.ret == pytest.ExitCode.USAGE_ERROR


def test_artifacts_include_pictures_or_say_why_not(pytester, tmp_path):
    pytest.importorskip("matplotlib")
    pytester.makepyfile(
        """
        import pytest
        import pytest_flockai as fa

        @pytest.mark.flockai(drone="crazyflie-2-1", pilot=fa.pilots.Hover(1.0, 0.5))
        def test_hover(flight):
            pass
        """
    )
    art = tmp_path / "art"
    pytester.runpytest("-p", "no:cacheprovider", f"--flockai-artifacts={art}").assert_outcomes(passed=1)
    names = sorted(p.name for p in art.rglob("*") if p.is_file())
    assert names == ["flight.energy.png", "flight.json", "flight.path.png", "flight.telemetry.csv"]
    import cv2
    img = cv2.imread(str(next(art.rglob("flight.energy.png"))))
    assert img is not None and img.shape[0] > 200 and img.shape[1] > 400


def test_fixtures_parametrized_indirectly(pytester):
    pytester.makepyfile(
        """
        import pytest
        import pytest_flockai as fa

        @pytest.mark.parametrize("drone", ["crazyflie-2-1", "generic-hexa-680"], indirect=True)
        @pytest.mark.parametrize("pilot", [fa.pilots.Hover(1.0, 0.5)], indirect=True)
        def test_each_drone(drone, flight):
            assert flight.scenario["drone"]["name"] == drone.name
            assert flight.scenario["pilot"]["altitude"] == 1.0
        """
    )
    res = pytester.runpytest("-p", "no:cacheprovider", "-v")
    res.assert_outcomes(passed=2)
    res.stdout.fnmatch_lines(["*test_each_drone*crazyflie-2-1*PASSED*",
                              "*test_each_drone*generic-hexa-680*PASSED*"])


def test_per_test_and_per_kpi_regression_thresholds(pytester):
    """pytest-benchmark can only gate the whole session; here each test (and each
    KPI of a test) may set its own regression threshold."""
    make(pytester, '''
@cf(max_regression=1.0)
def test_strict(flight):
    pass

@cf(max_regression={"energy_total_j": 50.0})
def test_lenient_on_energy(flight):
    pass

@cf(max_regression="lots")
def test_bad_setting(flight):
    pass
''')
    run(pytester, "--flockai-save", "base.json")
    base = load(pytester.path / "base.json")
    for name in ("test_strict", "test_lenient_on_energy"):
        base["tests"][f"test_flights.py::{name}"]["flight"]["energy_total_j"] *= 0.97   # 3% worse now
    (pytester.path / "base.json").write_text(json.dumps(base))
    res = run(pytester, "--flockai-baseline", "base.json")
    # default 5%: the 3% change passes, except in the test that allows only 1%
    res.assert_outcomes(passed=1, failed=1, errors=1)
    res.stdout.fnmatch_lines(["*max_regression = 'lots' is not allowed*",
                              "*KPI regression(s) against baseline *base.json (max 1%) in "
                              "test_flights.py::test_strict:*"])
