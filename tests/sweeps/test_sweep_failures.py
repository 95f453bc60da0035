"""A sweep never loses finished work: a variant that raises or kills its worker is a
row with its error, an interrupt returns the rows so far, a base the workers cannot
load and a sweep too large for the limits are ConfigErrors naming what to do."""

import json
import os
import signal
import subprocess
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import pandas as pd
import pytest
from sweep_faults import ExitOn, InterruptOn, RaiseOn

import pytest_flockai as fa
from pytest_flockai.cache import caching
from pytest_flockai.errors import ConfigError
from pytest_flockai.sweeps import executors
from pytest_flockai.sweeps.runner import SweepInterrupted

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[2]
PAYLOADS = [0.0, 0.002, 0.004]



def _default_sigint():
    """The child takes Ctrl-C as a shell's foreground job would, whatever this process
    inherited (a job started with ``&`` by a non-interactive shell ignores SIGINT, and
    an ignored signal stays ignored across exec)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _base(*components):
    return fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=1.0),
                      components=list(components))


def _alone(payload_kg):
    m = _base()
    m.drone.payload_kg = payload_kg
    return m.run().kpis


@pytest.mark.parametrize("workers", [1, 2])
def test_an_exception_in_one_variant_is_its_row_and_the_others_fly(workers):
    df = fa.sweep(_base(RaiseOn(0.002)), payload_kg=PAYLOADS, workers=workers,
                  budgets={"flight_time_s": "> 0 s"})
    assert list(df["error"]) == [None, "ZeroDivisionError: division by zero", None]
    assert list(df["end_reason"]) == ["landed", "error", "landed"]
    assert list(df["ok"]) == [True, False, True]
    assert "1 / 0" in df.attrs["tracebacks"][1] and set(df.attrs["tracebacks"]) == {1}
    assert df["energy_total_j"][2] == _alone(0.004)["energy_total_j"]


def test_a_worker_that_dies_marks_its_variant_and_the_others_come_back():
    df = fa.sweep(_base(ExitOn(0.002, code=9)), payload_kg=PAYLOADS + [0.006], workers=2)
    assert list(df["error"]) == [None, "worker died: exit 9", None, None]
    assert list(df["end_reason"]) == ["landed", "error", "landed", "landed"]
    for i in (0, 2, 3):
        assert df["energy_total_j"][i] == _alone(df["payload_kg"][i])["energy_total_j"]


def test_a_broken_pool_of_the_callers_is_rows_not_an_exception():
    with ProcessPoolExecutor(2) as pool:
        df = fa.sweep(_base(ExitOn(0.002, code=3)), payload_kg=PAYLOADS, executor=pool)
    died = df["error"].dropna()
    assert 1 in died.index and all(e.startswith("worker died: BrokenProcessPool") for e in died)
    assert df["error"].isna().sum() + len(died) == 3


def _python(code: str, **kw) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), str(ROOT / "tests"), str(ROOT / "tests" / "project")]))
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=env, timeout=300, check=False, **kw)


def test_a_class_defined_in_main_is_named_with_what_to_do():
    out = _python("""
import pytest_flockai as fa
class MyProbe(fa.Clocked):
    period_s = 1.0
    def step(self, t):
        self.advance_clock()
m = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(1.0, 1.0), components=[MyProbe()])
try:
    fa.sweep(m, payload_kg=[0.0, 0.002], workers=2)
except fa.errors.ConfigError as exc:
    print("ConfigError:", exc)
""")
    assert "ConfigError: sweep: a worker process cannot load the base mission" in out.stdout
    assert "MyProbe defined in __main__" in out.stdout and "move it into a module" in out.stdout


def test_a_script_without_a_main_guard_is_told_to_add_one(tmp_path):
    script = tmp_path / "unguarded.py"
    script.write_text("import pytest_flockai as fa\n"
                      "m = fa.Mission(fa.drone('crazyflie-2-1'), fa.pilots.Hover(1.0, 1.0))\n"
                      "fa.sweep(m, payload_kg=[0.0, 0.002], workers=2)\n")
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    out = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, env=env,
                         timeout=300, check=False)
    assert out.returncode == 1 and "BrokenProcessPool" not in out.stderr
    last = out.stderr.strip().splitlines()[-1]
    assert last.startswith("pytest_flockai.errors.ConfigError: sweep: the worker processes died "
                           "before flying any variant")
    assert 'if __name__ == "__main__":' in last


def test_samples_far_above_the_limit_are_refused_before_anything_is_made():
    with pytest.raises(ConfigError) as exc:
        fa.sweep(_base(), payload_kg=(0.0, 0.01), method="random", samples=10**7)
    assert "10,000,000 variants" in str(exc.value)
    assert "fa.limits.MAX_VARIANTS = 10000000" in str(exc.value)


def test_a_grid_above_the_limit_names_its_size_and_the_limit_can_be_raised(monkeypatch):
    grid = dict(payload_kg=list(range(100)), wind_mps=list(range(100)),
                mission_seed=list(range(100)))
    with pytest.raises(ConfigError) as exc:
        fa.sweep(_base(), **grid)
    assert "1,000,000 variants (100 payload_kg x 100 wind_mps x 100 mission_seed)" in str(exc.value)
    assert "pytest_flockai.limits.MAX_VARIANTS = 100,000" in str(exc.value)
    monkeypatch.setattr(fa.limits, "MAX_VARIANTS", 2)
    with pytest.raises(ConfigError, match="3 variants"):
        fa.sweep(_base(), payload_kg=PAYLOADS, workers=1)
    assert len(fa.sweep(_base(), payload_kg=PAYLOADS[:2], until=[0.5], workers=1)) == 2


def test_an_interrupt_returns_the_rows_finished_so_far():
    with pytest.warns(SweepInterrupted, match="1 of 3 variants"):
        df = fa.sweep(_base(InterruptOn(0.002)), payload_kg=PAYLOADS, workers=1)
    assert df.attrs["interrupted"] is True
    assert list(df["end_reason"]) == ["landed", "interrupted", "interrupted"]
    assert list(df["error"]) == [None, "interrupted", "interrupted"]
    assert df["energy_total_j"][0] == _alone(0.0)["energy_total_j"]


def test_an_interrupted_marked_sweep_fails_keeps_its_rows_and_stops_the_run(pytester):
    pytester.makepyfile("""
        import pytest
        import pytest_flockai as fa
        from sweep_faults import InterruptOn

        @pytest.fixture
        def mission():
            return fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(1.0, 1.0),
                              components=[InterruptOn(0.002)])

        @pytest.mark.flockai_sweep(payload_kg=[0.0, 0.002, 0.004], workers=1)
        def test_x(flockai_sweep):
            pass

        def test_never_run():
            pass
    """)
    result = pytester.runpytest("-p", "no:cacheprovider", "--flockai-json=r.json")
    assert result.ret == pytest.ExitCode.INTERRUPTED
    result.assert_outcomes(failed=1, warnings=1)
    result.stdout.fnmatch_lines(["*payload_kg=0.002*interrupted*", "*sweep of*was interrupted*"])
    (entry,) = json.loads((pytester.path / "r.json").read_text())["tests"]
    assert [r["end_reason"] for r in entry["sweep"]["rows"]] == ["landed", "interrupted",
                                                                  "interrupted"]
    assert entry["sweep"]["interrupted"] is True


def test_ctrl_c_during_a_pool_sweep_returns_the_finished_rows(tmp_path):
    """SIGINT to a script whose sweep waits on its pool: the rows so far come back."""
    marks = tmp_path / "marks"
    marks.mkdir()
    code = f"""
import json, warnings, sys
import pytest_flockai as fa
from sweep_faults import MarkAndWait
if __name__ == "__main__":
    m = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(1.0, 1.0),
                   components=[MarkAndWait(0.004, {str(marks)!r}, wait_s=60.0)])
    warnings.simplefilter("ignore")
    df = fa.sweep(m, payload_kg=[0.0, 0.002, 0.004, 0.006], workers=2)
    print(json.dumps([list(df["end_reason"]), df.attrs["interrupted"]]))
"""
    script = tmp_path / "ctrl_c.py"
    script.write_text(code)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), str(ROOT / "tests"), str(ROOT / "tests" / "project")]))
    proc = subprocess.Popen([sys.executable, str(script)], preexec_fn=_default_sigint,
                            stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env)
    try:
        deadline = time.monotonic() + 120
        while not any(marks.iterdir()):
            assert time.monotonic() < deadline and proc.poll() is None, proc.stderr.read()
            time.sleep(0.05)
        time.sleep(1.0)                 # the other worker finishes the variants left
        proc.send_signal(signal.SIGINT)
        out, _ = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(timeout=10)
    reasons, interrupted = json.loads(out.strip().splitlines()[-1])
    assert interrupted is True and reasons[2] == "interrupted"
    assert reasons[:2] == ["landed", "landed"] and reasons[3] in ("landed", "interrupted")


def test_the_progress_bar_counts_drone_seconds_and_variants(capsys):
    with caching(None):
        df = fa.sweep(_base(), payload_kg=PAYLOADS, until=[2.0], workers=1, progress=True)
    err = capsys.readouterr().err
    assert "6.00/6.00 drone-s" in err and "3/3 variants" in err and "100%" in err
    with caching(None):
        fa.sweep(_base(), payload_kg=PAYLOADS, until=[2.0], workers=1)   # stderr is no terminal
    assert capsys.readouterr().err == "" and len(df) == 3
    with caching(None):                 # flown until landed: the total is known after one lands
        landed = fa.sweep(_base(), payload_kg=PAYLOADS, workers=1, progress=True)
    err = capsys.readouterr().err
    total = f"{landed['sim_time_s'].sum():.1f}/{landed['sim_time_s'].sum():.1f} drone-s"
    assert "0.00/? drone-s" in err and total in err and "3/3 variants" in err


@pytest.mark.parametrize("kwargs, words", [
    (dict(executor=42), ["executor = 42", "concurrent.futures.Executor"]),
    (dict(executor="not an address"), ["executor = 'not an address'", "tcp://"]),
    (dict(batch_size=0), ["batch_size = 0", "integer >= 1"]),
    (dict(progress="yes"), ["progress = 'yes'", "True or False"]),
])
def test_bad_engine_settings_are_config_errors_naming_them(kwargs, words):
    with pytest.raises(ConfigError) as exc:
        fa.sweep(_base(), payload_kg=[0.0], **kwargs)
    assert all(w in str(exc.value) for w in words), str(exc.value)


def test_same_seed_same_rows_with_a_pool_of_the_callers():
    kw = dict(payload_kg=(0.0, 0.006), mission_seed=(0, 5), method="lhs", samples=4, seed=3)
    with caching(None), ProcessPoolExecutor(2) as pool:
        pd.testing.assert_frame_equal(fa.sweep(_base(), executor=pool, **kw),
                                      fa.sweep(_base(), workers=1, **kw))


def test_a_bad_sweep_executor_option_stops_pytest_naming_it(pytester):
    pytester.makepyfile("def test_x():\n    pass\n")
    bad = pytester.runpytest("--flockai-sweep-executor=not an address")
    assert bad.ret == pytest.ExitCode.USAGE_ERROR
    bad.stderr.fnmatch_lines([("*--flockai-sweep-executor = 'not an address' is not allowed*"
                               "scheduler address*")])
    pytester.makeini("[pytest]\nflockai_sweep_executor = tcp:/nowhere\n")
    bad = pytester.runpytest()
    assert bad.ret == pytest.ExitCode.USAGE_ERROR
    bad.stderr.fnmatch_lines(["*flockai_sweep_executor (ini) = 'tcp:/nowhere' is not allowed*"])


def test_an_address_where_no_scheduler_answers_is_a_config_error_naming_it(monkeypatch):
    pytest.importorskip("distributed")
    monkeypatch.setattr(executors, "CONNECT_TIMEOUT_S", 1.0)
    with pytest.raises(ConfigError) as exc:
        fa.sweep(_base(), payload_kg=[0.0, 0.002], executor="tcp://127.0.0.1:9")
    assert "executor = 'tcp://127.0.0.1:9': no Dask scheduler answered there" in str(exc.value)
