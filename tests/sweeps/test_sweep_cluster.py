"""fa.sweep on a real Dask cluster: a scheduler and two workers started as separate
processes (`dask scheduler`, `dask worker`) on 127.0.0.1, torn down at the end."""

import json
import os
import signal
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pandas as pd
import pytest
from sweep_faults import ExitOn, MarkAndWait, RaiseOn

import pytest_flockai as fa
from pytest_flockai.cache import FlightCache, caching

pytestmark = pytest.mark.slow

distributed = pytest.importorskip("distributed")

ROOT = Path(__file__).resolve().parents[2]
DASK = Path(sys.executable).with_name("dask")
START_S = 90.0        # the slowest start seen on a loaded 2-core machine was ~15 s
STOP_S = 10.0
NO_WAIT_S = 3.0       # how long a sweep here waits for a worker when none is left


def _base(**kw):
    return fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=1.0), **kw)


AXES = dict(payload_kg=[0.0, 0.004], mission_seed=[0, 1], wind_mps=[0.0, 3.0])


class Cluster:
    """`dask scheduler` and `dask worker` processes of one test module."""

    def __init__(self, folder: Path):
        self.folder, self.workers, self.client, self.logs = folder, [], None, []
        self.env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), str(ROOT / "tests"), str(ROOT / "tests" / "project")]),
                        MUJOCO_GL="egl")
        file = folder / "scheduler.json"
        self.scheduler = self._start("scheduler", "scheduler", "--host", "127.0.0.1", "--port",
                                     "0", "--no-dashboard", "--scheduler-file", str(file))
        deadline = time.monotonic() + START_S
        while not file.exists() or not file.read_text().strip():
            assert self.scheduler.poll() is None, self._log("scheduler")
            assert time.monotonic() < deadline, "no scheduler file after 90 s"
            time.sleep(0.2)
        self.address = json.loads(file.read_text())["address"]
        self.client = distributed.Client(self.address, timeout=START_S)

    def _start(self, name, *args):
        log = open(self.folder / f"{name}.log", "w")   # noqa: SIM115 - closed in stop()
        self.logs.append(log)
        return subprocess.Popen([str(DASK), *args], cwd=self.folder, env=self.env, stdout=log,
                                stderr=subprocess.STDOUT, start_new_session=True)

    def _log(self, name) -> str:
        return (self.folder / f"{name}.log").read_text()[-3000:]

    def ensure_workers(self, n: int = 2) -> None:
        """``n`` live workers (killed ones replaced), registered with the scheduler."""
        self.workers = [w for w in self.workers if w.poll() is None]
        while len(self.workers) < n:
            k = len(list(self.folder.glob("worker-*.log")))
            self.workers.append(self._start(f"worker-{k}", "worker", self.address, "--nthreads",
                                            "1", "--no-nanny", "--no-dashboard",
                                            "--local-directory", str(self.folder)))
        deadline = time.monotonic() + START_S
        while len(self.client.scheduler_info()["workers"]) != n:
            assert time.monotonic() < deadline, f"{n} workers not up after 90 s"
            time.sleep(0.2)

    def stop(self) -> None:
        if self.client is not None:
            self.client.close(timeout=STOP_S)
        for p in self.workers + [self.scheduler]:
            if p.poll() is None:
                p.terminate()
        for p in self.workers + [self.scheduler]:
            try:
                p.wait(timeout=STOP_S)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait(timeout=STOP_S)
        for log in self.logs:
            log.close()


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    if not DASK.exists():
        pytest.skip(f"no dask command beside {sys.executable}")
    c = Cluster(tmp_path_factory.mktemp("dask"))
    try:
        c.ensure_workers(2)
        yield c
    finally:
        procs = c.workers + [c.scheduler]
        c.stop()
        assert all(p.poll() is not None for p in procs), "a dask process outlived the fixture"


def test_a_sweep_through_the_cluster_equals_one_worker_row_for_row(cluster):
    cluster.ensure_workers(2)
    with caching(None):                     # every variant flies (no cache hits)
        one = fa.sweep(_base(), workers=1, **AXES)
        by_address = fa.sweep(_base(), executor=cluster.address, **AXES)
        by_client = fa.sweep(_base(), executor=cluster.client, batch_size=3, **AXES)
        by_executor = fa.sweep(_base(), executor=cluster.client.get_executor(), **AXES)
    pd.testing.assert_frame_equal(by_address, one)
    pd.testing.assert_frame_equal(by_client, one)
    pd.testing.assert_frame_equal(by_executor, one)
    assert len(one) == 8 and one["error"].isna().all()
    assert by_address.attrs["executor"] == cluster.address
    # both workers flew: each ran tasks of this module's sweeps
    ran = cluster.client.run(lambda: len(sys.modules["pytest_flockai.sweeps.worker"]._BASES))
    assert len(ran) == 2 and all(n >= 1 for n in ran.values())


def test_an_exception_in_a_variant_on_the_cluster_is_the_same_row_as_here(cluster):
    cluster.ensure_workers(2)
    base = _base(components=[RaiseOn(0.004)])
    here = fa.sweep(base, payload_kg=[0.0, 0.004, 0.008], workers=1)
    there = fa.sweep(base, payload_kg=[0.0, 0.004, 0.008], executor=cluster.address)
    pd.testing.assert_frame_equal(there, here)
    assert list(there["error"]) == [None, "ZeroDivisionError: division by zero", None]
    assert "1 / 0" in there.attrs["tracebacks"][1]


def test_the_flight_cache_in_a_shared_folder_is_written_by_the_workers(cluster, tmp_path):
    cluster.ensure_workers(2)
    with caching(FlightCache(tmp_path / "flights")):
        cold = fa.sweep(_base(), executor=cluster.address, payload_kg=[0.0, 0.004])
        warm = fa.sweep(_base(), executor=cluster.address, payload_kg=[0.0, 0.004])
    assert cold.attrs["cache"] == {"stored": 2}             # stored by the Dask workers
    assert warm.attrs["cache"] == {"hit": 2}                # read here: no task sent
    pd.testing.assert_frame_equal(warm, cold)


def test_a_worker_killed_mid_sweep_loses_no_finished_row(cluster, tmp_path):
    cluster.ensure_workers(2)
    axes = dict(payload_kg=[0.0, 0.001, 0.002, 0.003, 0.004, 0.005, 0.006, 0.007])
    marks = tmp_path / "marks"
    marks.mkdir()
    base = _base(components=[MarkAndWait(0.005, marks, wait_s=4.0)])
    with ThreadPoolExecutor(1) as pool:
        job = pool.submit(fa.sweep, base, executor=cluster.address, **axes)
        deadline = time.monotonic() + 120
        while not any(marks.iterdir()):
            assert time.monotonic() < deadline and not job.done(), "variant 5 never started"
            time.sleep(0.05)
        victim = int(next(marks.iterdir()).name)
        assert victim in [w.pid for w in cluster.workers]
        os.kill(victim, signal.SIGKILL)
        df = job.result(timeout=300)
    assert next(w for w in cluster.workers if w.pid == victim).wait(timeout=STOP_S) == -9
    reference = fa.sweep(_base(components=[MarkAndWait(0.005, tmp_path, wait_s=0.0)]),
                         workers=1, **axes)
    pd.testing.assert_frame_equal(df, reference)
    assert df["error"].isna().all() and len(df) == 8


def test_any_concurrent_futures_executor_gives_the_same_rows():
    with caching(None), ThreadPoolExecutor(2) as threads:
        one = fa.sweep(_base(), workers=1, **AXES)
        pd.testing.assert_frame_equal(fa.sweep(_base(), executor=threads, **AXES), one)
        pd.testing.assert_frame_equal(fa.sweep(_base(), executor=threads, batch_size=5, **AXES),
                                      one)


def test_the_pytest_option_points_marked_sweeps_at_the_scheduler(cluster, pytester):
    cluster.ensure_workers(2)
    pytester.makepyfile("""
        import pytest

        @pytest.mark.flockai_sweep(payload_kg=[0.0, 0.004], until=[1.0])
        @pytest.mark.kpi(energy_total_j="> 0 J")
        def test_x(flockai_sweep):
            assert flockai_sweep.attrs["executor"] == "Client"
            assert len(flockai_sweep) == 2 and flockai_sweep["ok"].all()
    """)
    result = pytester.runpytest("-p", "no:cacheprovider",
                                f"--flockai-sweep-executor={cluster.address}")
    result.assert_outcomes(passed=1)


@pytest.fixture
def short_wait():
    """The sweep waits NO_WAIT_S (not 30 s) for a worker when none is left."""
    import dask.config
    with dask.config.set({"distributed.scheduler.no-workers-timeout": f"{NO_WAIT_S}s"}):
        yield


def test_a_variant_that_kills_its_worker_costs_no_innocent_row(cluster, short_wait):
    """The innocent variants beside a variant that kills its worker get their real
    rows; the killer flies once more, alone, and its row names the two dead workers."""
    cluster.ensure_workers(2)
    addresses = set(cluster.client.scheduler_info()["workers"])
    axes = dict(payload_kg=[0.0, 0.001, 0.002, 0.003, 0.004])
    with caching(None):
        df = fa.sweep(_base(components=[ExitOn(0.002)]), executor=cluster.address, **axes)
        reference = fa.sweep(_base(), workers=1, **axes)
    assert len(df) == 5
    errors = df["error"].fillna("")
    guilty = df["payload_kg"] == 0.002
    assert errors[~guilty].eq("").all(), errors.tolist()
    pd.testing.assert_frame_equal(df[~guilty], reference[~guilty])
    (text,) = errors[guilty]
    assert text.startswith("worker died: ") and text.endswith("died under it (2 tries)"), text
    named = [a for a in addresses if a in text]
    assert len(named) == 2, (text, addresses)        # both workers, each named once
    assert df.loc[guilty, "end_reason"].item() == "error"
    # the killer took exactly two workers down: its second try was alone, and no third
    assert sum(w.poll() is not None for w in cluster.workers) == 2


def test_an_innocent_variant_in_the_killers_task_flies_again_alone(cluster, short_wait):
    """Two variants per task: the innocent one that flew in the same task as the
    killer flies again alone and gets its real row; the killer costs two workers."""
    cluster.ensure_workers(3)
    axes = dict(payload_kg=[0.0, 0.001, 0.002, 0.003, 0.004])
    with caching(None):
        df = fa.sweep(_base(components=[ExitOn(0.002)]), executor=cluster.address,
                      batch_size=2, **axes)
        reference = fa.sweep(_base(), workers=1, **axes)
    guilty = df["payload_kg"] == 0.002
    errors = df["error"].fillna("")
    assert errors[~guilty].eq("").all(), errors.tolist()
    pd.testing.assert_frame_equal(df[~guilty], reference[~guilty])
    assert errors[guilty].item().endswith("died under it (2 tries)"), errors.tolist()
    assert sum(w.poll() is None for w in cluster.workers) == 1


def test_a_sweep_whose_every_worker_dies_returns_with_rows_saying_why(cluster, short_wait,
                                                                      tmp_path):
    """Variants that kill every worker: the sweep waits NO_WAIT_S for a worker,
    then returns; the row that flew first is kept, the others say why they have none."""
    cluster.ensure_workers(2)
    axes = dict(payload_kg=[0.0, 0.002], mission_seed=[0, 1, 2])
    # the killers wait 1.5 s before they exit: a result finished before is back by then
    # (a result still on a worker when it dies is lost with it)
    killer = [MarkAndWait(0.002, tmp_path, wait_s=1.5), ExitOn(0.002)]
    t0 = time.monotonic()
    with caching(None):
        df = fa.sweep(_base(components=killer), executor=cluster.address, **axes)
    took = time.monotonic() - t0
    assert took < 90, took                           # bounded: flights + a few NO_WAIT_S
    assert len(df) == 6 and all(w.poll() is not None for w in cluster.workers)
    errors = df["error"].fillna("")
    killers = df["payload_kg"] == 0.002
    assert killers.sum() == 3
    # each row without a flight says why: its worker died, or no worker was left
    reasons = errors[killers]
    assert reasons.str.match(r"^(worker died: |not flown: no Dask worker left \(none "
                             r"joined tcp://127\.0\.0\.1:\d+ within 3 s)").all(), reasons.tolist()
    assert (df.loc[killers, "end_reason"] == "error").all()
    flew = errors[~killers] == ""
    assert flew.iloc[0], errors.tolist()             # the first variant flew before any death
    assert (errors[~killers][~flew].str.startswith("not flown: no Dask worker left")).all()
    # a sweep sent to the cluster that has no worker now waits NO_WAIT_S, then says so
    t0 = time.monotonic()
    with caching(None):                  # not from the flight cache (on under `pytest tests`)
        empty = fa.sweep(_base(), executor=cluster.client, payload_kg=[0.0, 0.004])
    assert NO_WAIT_S <= time.monotonic() - t0 < 30
    assert empty["error"].str.startswith("not flown: no Dask worker left").all()
