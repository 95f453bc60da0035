"""Per-task energy: ``<task>.energy_j`` moves as physics says between on board and
remote (the compute energy leaves the drone, the radio energy of the frames' bytes
arrives), and the tasks' figures plus the untasked remainder sum to the proc and
comm groups' totals; the remainder is what the same flight draws without tasks."""

from pathlib import Path

import pytest

import pytest_flockai as fa
from pytest_flockai.compute.latency import resolve_device

MODELS = Path(__file__).resolve().parents[2] / "fixtures" / "models"
PI4 = resolve_device("raspberry-pi-4", "device")


def _mission(*tasks):
    world = fa.World.urban(seed=2, size=(80.0, 80.0), people=30, crowds=[(0.0, 0.0, 12, 3.0)])
    return fa.Mission(fa.drone("dji-mavic-2-pro", device="raspberry-pi-4"),
                      fa.pilots.Hover(20.0, 12.0), world=world, tasks=list(tasks), seed=0)


def _task(name, execution):
    """On board it sends its counts only (alert="result"), no annotated frames."""
    return fa.Task(fa.ml.OnnxModel(MODELS / "crowd_tiny.onnx"), period_s=1.0, name=name,
                   execution=execution, alert="result")


@pytest.fixture(scope="module")
def flights():
    both = _mission(_task("near", "onboard"), _task("far", "remote")).run()
    bare = _mission().run()
    return both, bare


def test_compute_energy_leaves_the_drone_and_radio_energy_arrives_when_remote(flights):
    r, _ = flights
    k = r.kpis
    inf = [e for e in r.events if e.get("kind") == "inference"]
    near = [e for e in inf if e["task"] == "near" and e["ok"]]
    # on board: each inference's compute time at the Pi's active-over-idle power
    on = sum(e["compute_s"] for e in near) * (PI4.active_w - PI4.idle_w)
    assert k["near.compute_energy_j"] == pytest.approx(on, rel=1e-9)
    # far: JPEG encoding only (~1 ms a frame); near: the inference (~2 ms on the Pi 4 with
    # ONNX Runtime, the layer model of compute.predict_latency)
    assert k["near.compute_energy_j"] > 1.5 * k["far.compute_energy_j"] > 0
    sent = sum(e["tx_bytes"] for e in inf if e["task"] == "far")
    assert sent > 10 * sum(e["tx_bytes"] for e in near)                      # frames, not counts
    assert k["far.radio_energy_j"] > 10 * k["near.radio_energy_j"] > 0
    for t in ("near", "far"):
        assert k[f"{t}.energy_j"] == k[f"{t}.compute_energy_j"] + k[f"{t}.radio_energy_j"]


def test_tasks_plus_the_untasked_remainder_are_the_groups_and_the_taskless_flight(flights):
    r, bare = flights
    groups = r.energy_breakdown["proc"] + r.energy_breakdown["comm"]
    tasks = r.kpis["near.energy_j"] + r.kpis["far.energy_j"]
    assert tasks + r.kpis["energy_untasked_j"] == pytest.approx(groups, rel=1e-12)
    # the remainder is what the same flight draws in proc and comm without any task
    # (idle computer and radio, flight controller, sensors, telemetry traffic)
    assert r.kpis["energy_untasked_j"] == pytest.approx(
        bare.energy_breakdown["proc"] + bare.energy_breakdown["comm"], rel=1e-6)
    assert "energy_untasked_j" not in bare.kpis


def test_a_single_threaded_task_charges_a_quarter_of_the_pis_busy_power():
    """TF Lite runs one thread (of the Pi 4's four cores): its inferences are charged at a
    quarter of the busy power above idle, and cpu_time_s still counts their whole time."""
    task = fa.Task(fa.ml.OnnxModel(MODELS / "crowd_tiny.onnx"), period_s=1.0, name="lite",
                   alert="result", runtime="tflite")
    r = _mission(task).run()
    inf = [e for e in r.events if e.get("kind") == "inference" and e["task"] == "lite"]
    busy = sum(e["compute_s"] for e in inf if e["ok"])
    assert busy > 0
    assert r.kpis["lite.compute_energy_j"] == pytest.approx(
        busy * (PI4.active_w - PI4.idle_w) / 4, rel=1e-9)
    assert r.kpis["cpu_time_s"] == pytest.approx(busy, rel=1e-6)
