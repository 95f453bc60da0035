"""The batch split over the CPUs (``sweeps/batched/shards.py``): the same rows
bit for bit with one shard, two, and the default (one per CPU), and the sweep says how
many ran. Each case is a fresh process (the host devices are set once, before JAX's
client starts)."""

import json
import os
import subprocess
import sys

import pytest

import pytest_flockai as fa

SCRIPT = """
import json
import pytest_flockai as fa
m = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=1.0),
               wind=fa.Wind(mean=(1.0, 0.0, 0.0), gust_std=0.5))
df = fa.sweep(m, backend="jax", device="cpu", payload_kg=[0.0, 0.004, 0.008],
              mission_seed=[0, 1, 2, 3, 4, 5])
cols = [c for c in df.columns if c != "error"]
print(json.dumps({"shards": df.attrs["jax_cpu_shards"], "rows": df[cols].to_dict("list")}))
"""


def _sweep_in_a_process(tmp_path, shards) -> dict:
    env = {**os.environ, "FLOCKAI_JAX_CACHE": str(tmp_path / "jax-cache")}
    env.pop("FLOCKAI_JAX_CPU_SHARDS", None)
    env.pop("XLA_FLAGS", None)
    if shards is not None:
        env["FLOCKAI_JAX_CPU_SHARDS"] = shards
    out = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True,
                         env=env, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    return json.loads(out.stdout.strip().splitlines()[-1])


@pytest.mark.jax
@pytest.mark.slow
def test_one_two_or_one_shard_per_cpu_give_the_same_rows_bit_for_bit(tmp_path):
    pytest.importorskip("jax")
    pytest.importorskip("mujoco.mjx")
    one = _sweep_in_a_process(tmp_path, "1")
    two = _sweep_in_a_process(tmp_path, "2")
    every = _sweep_in_a_process(tmp_path, None)
    assert (one["shards"], two["shards"]) == (1, 2)
    assert every["shards"] == min(len(os.sched_getaffinity(0)), 18)
    assert one["rows"] == two["rows"] == every["rows"]             # bit for bit
    assert len(set(one["rows"]["energy_total_j"])) == 18            # the axes flew


@pytest.mark.parametrize("value", ["0", "-1", "two", "1.5", "all"])
def test_a_bad_shard_count_is_refused_naming_the_variable(monkeypatch, value):
    from pytest_flockai.sweeps.batched import shards

    monkeypatch.setenv("FLOCKAI_JAX_CPU_SHARDS", value)
    with pytest.raises(fa.ConfigError) as exc:
        shards.wanted()
    msg = str(exc.value)
    assert "FLOCKAI_JAX_CPU_SHARDS" in msg and repr(value) in msg and ">= 1" in msg


@pytest.mark.jax
def test_a_sweep_refuses_a_bad_shard_count_before_flying(monkeypatch):
    pytest.importorskip("jax")
    monkeypatch.setenv("FLOCKAI_JAX_CPU_SHARDS", "0")
    m = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=1.0))
    with pytest.raises(fa.ConfigError, match="FLOCKAI_JAX_CPU_SHARDS = '0'"):
        fa.sweep(m, backend="jax", payload_kg=[0.0])


def test_the_default_is_one_shard_per_cpu_the_process_may_use(monkeypatch):
    from pytest_flockai.sweeps.batched import shards

    monkeypatch.delenv("FLOCKAI_JAX_CPU_SHARDS", raising=False)
    assert shards.wanted() == len(os.sched_getaffinity(0))
    monkeypatch.setenv("FLOCKAI_JAX_CPU_SHARDS", "3")
    assert shards.wanted() == 3


@pytest.mark.slow
@pytest.mark.jax
def test_a_repeated_sweep_reuses_its_variants_and_a_changed_base_does_not():
    """The host side of a repeated sweep: the variants built once per base mission."""
    pytest.importorskip("jax")
    pytest.importorskip("mujoco.mjx")
    from pytest_flockai.sweeps.batched import setup

    m = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=1.0))
    setup._BUILT.clear()
    first = fa.sweep(m, backend="jax", payload_kg=[0.0, 0.004, 0.008])
    assert len(setup._BUILT) == 3
    again = fa.sweep(m, backend="jax", payload_kg=[0.0, 0.004, 0.008])
    assert len(setup._BUILT) == 3                                 # nothing built again
    cols = [c for c in first.columns if c != "error"]
    assert first[cols].equals(again[cols])
    m.pilot.altitude = 2.0                                         # a changed base: new variants
    higher = fa.sweep(m, backend="jax", payload_kg=[0.0, 0.004, 0.008])
    assert len(setup._BUILT) == 6
    assert (higher["energy_total_j"] > first["energy_total_j"]).all()
