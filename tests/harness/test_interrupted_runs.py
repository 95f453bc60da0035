"""The report side of reliability: a run cut off by Ctrl-C (once, or twice under ``-n 2``), by
SIGTERM, or by a dead xdist worker still writes a valid JSON report and JUnit file,
and says which tests did not finish. Real pytest processes, real signals."""

import json
import os
import signal
import subprocess
import sys
import time
import xml.etree.ElementTree as ET

import pytest

pytestmark = pytest.mark.slow

TESTS = '''
import os, pathlib
import pytest
import pytest_flockai as fa

def fly(duration, seed=0):
    return fa.Mission(fa.drone("crazyflie-2-1"),
                      fa.pilots.Hover(altitude=1.0, duration=duration), seed=seed).run()

@pytest.mark.kpi(flight_time_s=">= 1 s")
def test_a_done():
    fly(2.0)

@pytest.mark.kpi(flight_time_s=">= 1 s")
def test_b_long():
    fly(2.0)
    pathlib.Path("started-" + os.environ.get("PYTEST_XDIST_WORKER", "main")).write_text(
        str(os.getpid()))
    # flights until the signal comes: one hover ends at battery depletion (about 400 s
    # simulated, seconds of wall time), so one alone could end before a loaded machine
    # sends the signal; each flight has its own seed (never a cache hit)
    seed = 1
    while True:
        fly(100000.0, seed=seed)
        seed += 1
'''


def _default_sigint():
    """The child takes Ctrl-C as a shell's foreground job would, whatever this process
    inherited (a job started with ``&`` by a non-interactive shell ignores SIGINT, and
    an ignored signal stays ignored across exec)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def start(pytester, *args):
    pytester.makepyfile(test_cut=TESTS)
    cmd = [sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-p", "no:randomly",
           "--flockai-json", "r.json", "--junitxml", "j.xml", *args]
    return subprocess.Popen(cmd, cwd=pytester.path, preexec_fn=_default_sigint,
                            stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)


def wait_started(pytester, proc, timeout=120.0):
    t0 = time.monotonic()
    while not list(pytester.path.glob("started-*")):
        assert proc.poll() is None, proc.stdout.read()
        assert time.monotonic() - t0 < timeout, "the long test never started"
        time.sleep(0.1)
    time.sleep(0.5)      # inside the long flight now


def finish(proc, timeout=120.0):
    out, _ = proc.communicate(timeout=timeout)
    return proc.returncode, out


def check_reports(pytester, cut_outcome):
    doc = json.loads((pytester.path / "r.json").read_text())
    tests = {t["nodeid"].split("::")[-1]: t for t in doc["tests"]}
    assert tests["test_b_long"]["outcome"] == cut_outcome, tests["test_b_long"]
    assert tests["test_b_long"]["message"]
    assert tests["test_a_done"]["outcome"] in ("passed", cut_outcome)
    root = ET.parse(pytester.path / "j.xml").getroot()        # well-formed
    assert root.tag == "testsuites"
    return doc, tests


def test_sigint_marks_the_cut_test_interrupted(pytester):
    proc = start(pytester)
    wait_started(pytester, proc)
    proc.send_signal(signal.SIGINT)
    rc, out = finish(proc)
    assert rc == pytest.ExitCode.INTERRUPTED, out
    doc, tests = check_reports(pytester, "interrupted")
    assert doc["interrupted"] is True
    assert tests["test_a_done"]["outcome"] == "passed"


def test_sigterm_still_writes_the_reports(pytester):
    proc = start(pytester)
    wait_started(pytester, proc)
    proc.send_signal(signal.SIGTERM)
    rc, out = finish(proc)
    assert rc == pytest.ExitCode.INTERRUPTED, out
    check_reports(pytester, "interrupted")


def test_double_sigint_under_xdist_still_writes_the_reports(pytester):
    pytest.importorskip("xdist")
    proc = start(pytester, "-n", "2")
    wait_started(pytester, proc)
    proc.send_signal(signal.SIGINT)
    time.sleep(0.3)
    proc.send_signal(signal.SIGINT)
    rc, out = finish(proc)
    assert rc == pytest.ExitCode.INTERRUPTED, out
    check_reports(pytester, "interrupted")


def test_a_killed_xdist_worker_is_reported_as_crashed(pytester):
    pytest.importorskip("xdist")
    proc = start(pytester, "-n", "2")
    wait_started(pytester, proc)
    (started,) = pytester.path.glob("started-gw*")
    victim = int(started.read_text())      # the worker running the long test
    assert victim != proc.pid
    os.kill(victim, signal.SIGKILL)
    rc, out = finish(proc)
    assert rc == pytest.ExitCode.TESTS_FAILED, out
    doc, tests = check_reports(pytester, "crashed")
    assert "crashed while running" in tests["test_b_long"]["message"]
