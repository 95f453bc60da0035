"""Issues 16 and 17 (reports): JUnit valid against the schema pytest targets, files
that follow the umask, the report writer refusing what it would destroy, a report
that cannot be written at the end warning instead of failing the run, and budgets
and baselines that cannot silently stop gating.

tests/reports/schemas/junit-10.xsd is the schema pytest validates its own xunit2 output
against (from pytest 9.2.0's source distribution, testing/example_scripts/; source
and checksum in the file's first comment)."""

import json
import os
import socket
import stat
from pathlib import Path

import pytest

import pytest_flockai as fa
from pytest_flockai import budgets
from pytest_flockai.errors import ConfigError
from pytest_flockai.reports import files as report

xmlschema = pytest.importorskip("xmlschema")
SCHEMA = Path(__file__).parent / "schemas" / "junit-10.xsd"

TESTS = '''
import pytest
import pytest_flockai as fa

def fly(duration=1.0, name=None):
    return fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=duration),
                      name=name).run()

@pytest.mark.kpi(flight_time_s=">= 1 s")
def test_one():
    fly()

def test_two():
    fly(name="a")
    fly(name="b")

@pytest.mark.kpi(flight_time_s=">= 1 h")
def test_broken():
    fly()

def test_plain():
    pass
'''


def run(pytester, *args):
    return pytester.runpytest_inprocess("-p", "no:cacheprovider", *args)


@pytest.mark.parametrize("family", ["xunit2", "xunit1"])
def test_junit_is_valid_against_the_schema(pytester, family):
    pytester.makepyfile(test_j=TESTS)
    res = run(pytester, "--junitxml", "j.xml", "-o", f"junit_family={family}")
    res.assert_outcomes(passed=3, failed=1)
    res.stdout.fnmatch_lines(["*KPIs are in --junitxml as suite properties*"])
    schema = xmlschema.XMLSchema(SCHEMA)
    path = pytester.path / "j.xml"
    if family == "xunit1":
        # the legacy family has pytest's own testcase attributes `file` and `line`, which
        # the schema does not know (with or without this plugin): everything else is valid
        import xml.etree.ElementTree as ET
        tree = ET.parse(path)
        for tc in tree.getroot().iter("testcase"):
            assert tc.get("file") == "test_j.py"
            tc.attrib.pop("file"), tc.attrib.pop("line")
        tree.write(path)
    errors = list(schema.iter_errors(str(path)))
    assert errors == []
    text = path.read_text()
    assert 'name="flockai[test_j.py::test_one].flight_time_s"' in text
    assert 'name="flockai[test_j.py::test_two].b.energy_total_j"' in text


def test_written_files_follow_the_umask(pytester):
    pytester.makepyfile(test_j=TESTS)
    old = os.umask(0o022)
    try:
        run(pytester, "--flockai-json", "r.json", "--flockai-save", "b.json")
        r = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=1.0)).run()
        r.save(pytester.path / "flight.csv")
        os.umask(0o077)
        report.write_json_atomic(pytester.path / "private.json", {})
    finally:
        os.umask(old)
    for name in ("r.json", "b.json", "flight.csv"):
        assert stat.S_IMODE((pytester.path / name).stat().st_mode) == 0o644, name
    assert stat.S_IMODE((pytester.path / "private.json").stat().st_mode) == 0o600


@pytest.mark.parametrize("case", ["fifo", "socket", "device", "junit", "save", "empty"])
def test_the_report_writer_refuses_what_it_would_destroy(pytester, case):
    """Never the system's /dev/null: a writer without this check replaces it (it did,
    on this machine, when these tests ran against the code before the fix)."""
    pytester.makepyfile(test_j=TESTS)
    if case == "fifo":
        os.mkfifo(pytester.path / "pipe")
        args, message = ["--flockai-json", "pipe"], "*/pipe' is a special file*"
    elif case == "socket":
        sock = socket.socket(socket.AF_UNIX)
        sock.bind(str(pytester.path / "sock"))
        args, message = ["--flockai-json", "sock"], "*/sock' is a special file*"
    elif case == "device":
        try:      # a null device of our own, in the test's folder (needs root)
            os.mknod(pytester.path / "null", 0o666 | stat.S_IFCHR, os.makedev(1, 3))
        except PermissionError:
            pytest.skip("creating a device node needs root")
        args, message = ["--flockai-json", "null"], "*/null' is a special file*"
    elif case == "junit":
        args, message = ["--flockai-json", "x.xml", "--junitxml", "./x.xml"], \
            "*--junitxml and --flockai-json name the same file*"
    elif case == "save":
        args, message = ["--flockai-json=r.json", "--flockai-save=r.json"], \
            "*--flockai-save and --flockai-json name the same file*"
    else:
        args, message = ["--flockai-json", ""], "*--flockai-json = '' is not allowed*"
    res = run(pytester, *args)
    assert res.ret == pytest.ExitCode.USAGE_ERROR
    res.stderr.fnmatch_lines([message])
    if case == "device":
        assert stat.S_ISCHR(os.stat(pytester.path / "null").st_mode)   # left as it was


def test_a_report_that_cannot_be_written_at_the_end_warns_and_keeps_the_verdicts(pytester):
    """The report's folder is replaced by a file while the tests run (as a disk that
    fills up or a folder made read-only): the run ends with the tests' own exit
    status, the terminal summary and one warning, not an OSError traceback."""
    pytester.makepyfile(test_gone='''
import shutil, pathlib
import pytest_flockai as fa

def test_flies_and_removes_the_folder():
    fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=1.0)).run()
    shutil.rmtree("out")
    pathlib.Path("out").write_text("not a folder any more")
''')
    (pytester.path / "out").mkdir()
    res = run(pytester, "--flockai-json", "out/r.json", "--flockai-artifacts", "out/art")
    assert res.ret == pytest.ExitCode.OK
    res.assert_outcomes(passed=1, warnings=1)
    out = res.stdout.str()
    assert out.count("the JSON report could not be written to") == 1
    assert "artifacts of test_gone.py" in out and "INTERNALERROR" not in out
    res.stdout.fnmatch_lines(["*= flockai KPIs =*"])


@pytest.mark.parametrize("text", ["<= 1e999 J", ">= " + "9" * 400 + " s"])
def test_a_budget_limit_that_overflows_is_refused(text):
    kpi = "energy_total_j" if "J" in text else "flight_time_s"
    with pytest.raises(ConfigError, match=f"KPI {kpi}: budget .* is not a finite number"):
        budgets.parse(kpi, text)


@pytest.mark.parametrize("value", ["NaN", "Infinity", "-Infinity", "1e309", "true", '"12"'])
def test_a_baseline_value_that_cannot_gate_is_refused(tmp_path, value):
    path = tmp_path / "b.json"
    path.write_text('{"schema": "pytest-flockai-baseline/1", "tests": {"t.py::test": '
                    f'{{"flight": {{"energy_total_j": {value}}}}}}}}}')
    with pytest.raises(report.ReportError, match=r"t.py::test flight 'flight' KPI "
                                                 r"'energy_total_j' = .* is not allowed; "
                                                 r"expected a finite number"):
        report.load_baseline(path)


def test_a_saved_baseline_with_a_non_finite_kpi_still_loads(tmp_path):
    """Non-finite KPIs are written as null; null is "not compared", not an error."""
    path = tmp_path / "b.json"
    report.write_json_atomic(path, report.baseline_from_tests(
        [{"nodeid": "t.py::test", "flights": [{"name": "flight",
                                               "kpis": {"a.b": float("nan"), "c.d": 1.0}}]}]))
    assert report.load_baseline(path) == {"t.py::test": {"flight": {"a.b": None, "c.d": 1.0}}}
    assert json.loads(path.read_text())["tests"]["t.py::test"]["flight"]["a.b"] is None
