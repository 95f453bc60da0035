"""Every report writer on a full disk, a folder that went away, or a path another
report already names: a warning, once, and pytest's exit status as the tests made
it; files written atomically (the old file, or none, never a cut-off one)."""

import os
import subprocess
import uuid
from pathlib import Path

import pytest

import pytest_flockai as fa
from pytest_flockai.errors import ConfigError, WriteError
from pytest_flockai.reports import files as report

pytest_plugins = ["pytester"]

BODY = '''
import pytest
import pytest_flockai as fa

@pytest.mark.flockai(drone="crazyflie-2-1", pilot=fa.pilots.Hover(altitude=1.0, duration=1.0))
def test_flies(flight):
    assert flight.kpis["crashed"] == 0
'''


@pytest.fixture
def full_disk():
    """A 64 KiB tmpfs, filled up (needs root: skipped elsewhere)."""
    where = Path(f"/tmp/flockai-full-{uuid.uuid4().hex[:8]}")
    where.mkdir()
    ok = os.geteuid() == 0 and subprocess.run(
        ["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(where)],
        capture_output=True).returncode == 0
    if not ok:
        where.rmdir()
        pytest.skip("a small tmpfs cannot be mounted here (needs root)")
    try:
        with open(where / "filler", "wb") as fh:
            try:
                fh.write(bytes(1 << 20))
            except OSError:
                pass
        yield where
    finally:
        subprocess.run(["umount", str(where)], check=False)
        where.rmdir()


def test_reports_on_a_full_disk_warn_and_keep_the_exit_status(pytester, full_disk):
    pytester.makepyfile(BODY)
    res = pytester.runpytest("-p", "no:randomly", f"--flockai-md={full_disk}/r.md",
                             f"--flockai-html={full_disk}/r.html",
                             f"--flockai-json={full_disk}/r.json",
                             f"--flockai-save={full_disk}/b.json")
    assert res.ret == 0
    res.assert_outcomes(passed=1)
    out = res.stdout.str()
    assert "Traceback" not in out and "INTERNALERROR" not in out
    for what in ("Markdown summary", "HTML dashboard", "JSON report", "baseline"):
        assert f"the {what} could not be written" in out, what
    assert sorted(p.name for p in full_disk.iterdir()) == ["filler"]   # no temporary left


def test_reports_into_a_folder_removed_during_the_run_warn(pytester):
    pytester.makepyfile(BODY + '''

def test_removes_the_folder():
    import shutil
    shutil.rmtree("gone")
''')
    (pytester.path / "gone").mkdir()
    res = pytester.runpytest("-p", "no:randomly", "--flockai-md=gone/r.md",
                             "--flockai-html=gone/r.html")
    assert res.ret == 0
    out = res.stdout.str()
    assert "the Markdown summary could not be written to" in out
    assert "the HTML dashboard could not be written to" in out and "INTERNALERROR" not in out


@pytest.mark.parametrize("a,b", [("--flockai-md", "--flockai-json"),
                                 ("--flockai-html", "--junitxml"),
                                 ("--flockai-md", "--flockai-html"),
                                 ("--flockai-save", "--flockai-md")])
def test_two_reports_naming_one_file_are_a_usage_error(pytester, a, b):
    pytester.makepyfile(BODY)
    res = pytester.runpytest(f"{a}=same.out", f"{b}=same.out")
    assert res.ret == pytest.ExitCode.USAGE_ERROR
    assert "name the same file" in res.stderr.str()
    assert not (pytester.path / "same.out").exists()


def test_a_link_to_another_report_is_the_same_file(pytester):
    pytester.makepyfile(BODY)
    (pytester.path / "r.json").write_text("{}")
    (pytester.path / "alias.md").symlink_to(pytester.path / "r.json")
    res = pytester.runpytest("--flockai-json=r.json", "--flockai-md=alias.md")
    assert res.ret == pytest.ExitCode.USAGE_ERROR and "name the same file" in res.stderr.str()


def test_artifacts_on_a_full_disk_leave_no_cut_off_file(full_disk, tmp_path):
    r = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(1.0, 5.0)).run()
    with pytest.raises(WriteError, match="telemetry.csv"):
        report.write_artifacts(full_disk, "t.py::test_a", "flight", r)
    left = [p for p in full_disk.rglob("*") if p.is_file() and p.name != "filler"]
    assert left == []                                # not a 0-byte nor an 8192-byte CSV
    folder = report.write_artifacts(tmp_path, "t.py::test_a", "flight", r)
    assert sorted(p.name for p in folder.iterdir() if not p.name.startswith("."))[:2] == [
        "flight.energy.png", "flight.json"]


def test_flight_result_save_names_the_file(full_disk, tmp_path):
    r = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(1.0, 5.0)).run()
    with pytest.raises(WriteError, match="out.csv.*No space left"):
        r.save(full_disk / "out.csv")
    assert not list(full_disk.glob(".out.csv*"))
    (tmp_path / "d.csv").mkdir()
    with pytest.raises(ConfigError, match="is a folder"):
        r.save(tmp_path / "d.csv")
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(WriteError, match="cannot create folder"):
        r.save(blocker / "sub" / "r.csv")
    with pytest.raises(WriteError, match="/dev/full.*device"):
        report.write_json_atomic(Path("/dev/full"), {})


def test_a_baseline_that_is_a_folder_says_so(tmp_path):
    with pytest.raises(report.ReportError, match="is a folder"):
        report.load_baseline(tmp_path)
    with pytest.raises(report.ReportError, match="MAX_JSON_DEPTH"):
        report.load_baseline(_deep(tmp_path / "deep.json"))


def test_a_deep_baseline_is_a_usage_error_not_an_internal_error(pytester):
    pytester.makepyfile(BODY)
    _deep(pytester.path / "deep.json")
    res = pytester.runpytest("--flockai-baseline=deep.json")
    assert res.ret == pytest.ExitCode.USAGE_ERROR and "INTERNALERROR" not in res.stdout.str()
    assert "MAX_JSON_DEPTH" in res.stderr.str()


def test_the_markdown_summary_escapes_html_in_test_ids():
    from pytest_flockai.reports import markdown
    doc = report.build_report([{"nodeid": "t.py::test[<img src=x onerror=alert(1)>]",
                                "outcome": "passed", "flights": [
                                    {"name": "f<script>", "kpis": {"flight_time_s": 1.0}}],
                                "budgets": [], "regressions": []}])
    text = markdown.job_summary(doc)
    assert "<img" not in text and "<script>" not in text and "&lt;img" in text


def _deep(p):
    p.write_text("[" * 50_000 + "]" * 50_000)
    return p
