"""ML tasks flown in missions (the must-shows at mission level).

The model here is a PythonModel with the shipped CNN's MAC count (modeled
latency depends only on MACs and the device): the relations below hold for
any model of that cost. example_tests/ fly the trained ONNX models.
"""

import numpy as np
import pytest

import pytest_flockai as fa
from pytest_flockai.ml import PythonModel

CNN_MACS = 5.26e8          # fixtures/models/crowd_cnn.onnx at 320x240


def _count_bright(frame):
    # a cheap real computation on the real rendered frame
    return float((frame.mean(axis=2) > 200).sum() // 50)


@pytest.fixture(scope="module")
def world():
    return fa.World.urban(seed=3, size=(160.0, 160.0), people=40, crowds=[(40.0, 30.0, 30, 4.0)],
                          max_building_height=20.0)


def _fly(world, tasks=(), **kw):
    pilot = fa.pilots.ZigZag(area=((-60, -60), (60, 60)), altitude=30, spacing=30, speed=8)
    return fa.Mission(fa.drone("dji-mavic-2-pro"), pilot, world=world, tasks=tasks, seed=0, **kw).run()


@pytest.fixture(scope="module")
def three_runs(world):
    model = PythonModel(_count_bright, macs=CNN_MACS, name="cnn")
    none = _fly(world)
    onboard = _fly(world, [fa.Task(model, period_s=1.0, execution="onboard", device="raspberry-pi-4")])
    # a slow link: the 64 kbit/s SiK telemetry radio many hobby drones carry
    remote = _fly(world, [fa.Task(model, period_s=1.0, execution="remote", link="sik-915")])
    return none, onboard, remote


@pytest.mark.slow
def test_onboard_costs_processing_energy_and_flight_time(three_runs):
    none, onboard, _ = three_runs
    assert onboard.kpis["energy_proc_j"] > none.kpis["energy_proc_j"]
    assert onboard.kpis["endurance_s"] < none.kpis["endurance_s"]
    assert onboard.kpis["cpu_utilization"] > 0.2 and none.kpis["cpu_utilization"] == 0.0
    b = onboard.energy_breakdown
    assert b["proc.soc.active"] > 0 and none.energy_breakdown["proc.soc.active"] == 0


def test_remote_moves_cost_to_comm_with_higher_latency_over_a_slow_link(three_runs):
    none, onboard, remote = three_runs
    assert remote.kpis["energy_comm_j"] > onboard.kpis["energy_comm_j"] > 0
    assert remote.kpis["energy_proc_j"] < onboard.kpis["energy_proc_j"]
    assert remote.kpis["kbytes_out"] > 5 * onboard.kpis["kbytes_out"]
    assert remote.kpis["inference_latency_p50_s"] > onboard.kpis["inference_latency_p50_s"]
    assert remote.kpis["endurance_s"] > onboard.kpis["endurance_s"]


def test_inference_events_telemetry_and_kpis(three_runs):
    _, onboard, _ = three_runs
    inf = [e for e in onboard.events if e["kind"] == "inference"]
    # one event per inference started: the successful ones and the failed ones
    assert len(inf) == onboard.kpis["inference_count"] + onboard.kpis["inference_failures"] > 0
    assert all("x" in e and e["latency_s"] > 0 for e in inf)
    assert "people_in_view" in onboard.telemetry and onboard.telemetry.people_in_view.max() > 10
    assert "cnn.inference_count" in onboard.kpis
    assert onboard.kpis["cnn.inference_latency_p50_s"] == onboard.kpis["inference_latency_p50_s"]
    assert 0 <= onboard.kpis["count_mae"] and 0 <= onboard.kpis["mem_utilization"] <= 1


def test_raspberry_pi_drops_frames_jetson_does_not(world):
    big = PythonModel(lambda f: 0.0, macs=3e9, name="big")
    pi = _fly(world, [fa.Task(big, period_s=0.5, device="raspberry-pi-4")], until=60.0)
    jet = _fly(world, [fa.Task(big, period_s=0.5, device="jetson-nano-10w")], until=60.0)
    assert pi.kpis["frames_dropped"] > 10
    assert jet.kpis["frames_dropped"] == 0 and jet.kpis["inference_count"] > pi.kpis["inference_count"]


@pytest.mark.slow
def test_modeled_latency_identical_measured_reports_spread(world):
    m = PythonModel(_count_bright, macs=CNN_MACS, name="cnn")
    a = _fly(world, [fa.Task(m, period_s=2.0)], until=60.0)
    b = _fly(world, [fa.Task(m, period_s=2.0)], until=60.0)
    assert a.kpis["inference_latency_p50_s"] == b.kpis["inference_latency_p50_s"]
    assert a.kpis == b.kpis
    meas = _fly(world, [fa.Task(m, period_s=2.0, latency="measured")], until=60.0)
    lat = [e["latency_s"] for e in meas.events if e["kind"] == "inference"]
    assert len(lat) > 5 and np.std(lat) > 0


def test_model_that_raises_is_recorded_and_flight_goes_on(world):
    def broken(frame):
        raise ValueError("bad tensor")
    r = _fly(world, [fa.Task(PythonModel(broken, macs=1e6, name="broken"), period_s=2.0)], until=40.0)
    assert r.end_reason == "time" and r.kpis["inference_failures"] > 5
    errs = [e for e in r.events if e["kind"] == "inference" and not e["ok"]]
    assert errs and "bad tensor" in errs[0]["error"]


def test_task_configuration_errors():
    d = fa.drone("crazyflie-2-1")
    m = PythonModel(lambda f: 0, macs=1e6)
    with pytest.raises(fa.ConfigError, match="no \\[camera\\] section"):
        fa.Mission(d, fa.pilots.Hover(1, 1), tasks=[fa.Task(m)])
    with pytest.raises(fa.ConfigError, match="sensor 'lidar'"):
        fa.Mission(fa.drone("dji-mavic-2-pro"), fa.pilots.Hover(1, 1), tasks=[fa.Task(m, sensor="lidar")])
    with pytest.raises(fa.ConfigError, match="different computers"):
        fa.Mission(fa.drone("dji-mavic-2-pro"), fa.pilots.Hover(1, 1),
                   tasks=[fa.Task(m, name="a"), fa.Task(m, name="b", device="jetson-nano-5w")])
    with pytest.raises(fa.ConfigError, match="period_s"):
        fa.Task(m, period_s=0)
    with pytest.raises(fa.ConfigError, match="unknown device"):
        fa.Task(m, device="raspberry-pi-5x")


def test_dataset_export_from_a_flight(world, tmp_path):
    r = _fly(world, dataset_dir=tmp_path / "ds", dataset_period_s=5.0, until=60.0)
    files = sorted((tmp_path / "ds").iterdir())
    pngs = [f for f in files if f.suffix == ".png"]
    assert len(pngs) >= 8 and any(f.suffix == ".csv" for f in files)
    assert r.kpis["crashed"] == 0


def test_several_tasks_with_different_periods(world):
    fast = fa.Task(PythonModel(_count_bright, macs=2e6, name="fast"), period_s=1.0)
    slow = fa.Task(PythonModel(_count_bright, macs=CNN_MACS, name="slow"), period_s=5.0)
    r = _fly(world, [fast, slow], until=60.0)
    k = r.kpis
    assert k["fast.inference_count"] > 4 * k["slow.inference_count"] > 0
    assert k["inference_count"] == k["fast.inference_count"] + k["slow.inference_count"]
    assert k["slow.inference_latency_p50_s"] > k["fast.inference_latency_p50_s"]
    assert k["cpu_time_s"] == pytest.approx(k["fast.cpu_time_s"] + k["slow.cpu_time_s"])


def test_on_board_tasks_share_one_computer(world):
    """Two heavy on-board tasks cannot both run on one Raspberry Pi at once: one
    waits for the other, the busy time never exceeds the flight time, and as the
    waiting makes each task slower than its period, frames are dropped."""
    a = fa.Task(PythonModel(lambda f: 0.0, macs=1.2e9, name="a"), period_s=1.0)
    b = fa.Task(PythonModel(lambda f: 0.0, macs=1.2e9, name="b"), period_s=1.0)
    r = _fly(world, [a, b], until=60.0)
    k = r.kpis
    assert k["cpu_utilization"] <= 1.0
    assert k["cpu_time_s"] <= r.sim_time_s
    assert k["frames_dropped"] > 0
    inf = sorted((e["t_start"], e["t_start"] + e["compute_s"]) for e in r.events
                 if e["kind"] == "inference" and e["ok"])
    assert all(s2 >= e1 - 1e-9 for (_, e1), (s2, _) in zip(inf, inf[1:]))   # no overlap
