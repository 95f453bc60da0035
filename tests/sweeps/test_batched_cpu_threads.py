"""The XLA CPU threads of the batched backend (``sweeps/batched/cpu_threads.py``): the
batch starts JAX's CPU client on one thread unless ``$FLOCKAI_JAX_CPU_THREADS=all``, the
rows do not depend on it, and the sweep says which ran. Each case is a fresh process
(the client starts once per process)."""

import json
import os
import subprocess
import sys

import pytest

import pytest_flockai as fa

SCRIPT = """
import json, sys
import pytest_flockai as fa
m = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=1.0),
               wind=fa.Wind(mean=(1.0, 0.0, 0.0), gust_std=0.5))
df = fa.sweep(m, backend="jax", device="cpu", payload_kg=[0.0, 0.004, 0.008], mission_seed=[0, 1])
cols = [c for c in df.columns if c != "error"]
import os
every_thread = {frozenset(os.sched_getaffinity(int(t))) for t in os.listdir("/proc/self/task")}
print(json.dumps({"threads": df.attrs["jax_cpu_threads"], "rows": df[cols].to_dict("list"),
                  "all_threads_on_every_cpu": every_thread == {frozenset(os.sched_getaffinity(0))}}))
"""


def _sweep_in_a_process(tmp_path, threads, first="") -> dict:
    env = {**os.environ, "FLOCKAI_JAX_CPU_THREADS": threads,
           "FLOCKAI_JAX_CACHE": str(tmp_path / "jax-cache")}
    out = subprocess.run([sys.executable, "-c", first + SCRIPT], capture_output=True, text=True,
                         env=env, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    return json.loads(out.stdout.strip().splitlines()[-1])


@pytest.mark.jax
@pytest.mark.slow
@pytest.mark.skipif(not os.path.isdir("/proc/self/task"), reason="Linux: thread affinity")
def test_one_thread_or_all_the_same_rows_and_the_sweep_says_which(tmp_path):
    pytest.importorskip("jax")
    pytest.importorskip("mujoco.mjx")
    one = _sweep_in_a_process(tmp_path, "1")
    every = _sweep_in_a_process(tmp_path, "all")
    before = _sweep_in_a_process(tmp_path, "1", first="import jax; jax.devices()\n")
    assert (one["threads"], every["threads"], before["threads"]) == (
        "1 thread", "all CPUs", "as started before")
    assert one["rows"] == every["rows"] == before["rows"]           # bit for bit
    # the client's own threads are not left on the one CPU it was started with
    assert one["all_threads_on_every_cpu"] and every["all_threads_on_every_cpu"]
    assert len(set(one["rows"]["energy_total_j"])) == 6             # the axes flew


@pytest.mark.jax
def test_a_bad_thread_setting_is_refused_naming_the_variable(monkeypatch):
    pytest.importorskip("jax")
    from pytest_flockai.sweeps.batched import cpu_threads

    monkeypatch.setenv("FLOCKAI_JAX_CPU_THREADS", "2")
    with pytest.raises(fa.ConfigError, match=r"FLOCKAI_JAX_CPU_THREADS = '2' .* allowed: 1 .* all"):
        cpu_threads.wanted()
    monkeypatch.setenv("FLOCKAI_JAX_CPU_THREADS", "ALL")
    assert cpu_threads.wanted() == "all"
