"""A task does not silently replace the drone's on-board computer.

``Task(device=None)`` (the default) runs on the drone's own computer; a task that
names another computer carries it as a second one: added, powered and reported.
Energies are MuJoCo flights of the blueprints; the computers' idle/active draw
comes from ``compute/devices.py`` (sources cited there)."""

import pytest

import pytest_flockai as fa
from pytest_flockai.compute import device
from pytest_flockai.errors import ConfigError
from pytest_flockai.ml.models import PythonModel

MODEL = PythonModel(lambda f: 0.0, macs=3e8, name="cnn")


def fly(drone, tasks=(), **kw):
    return fa.Mission(drone, fa.pilots.Hover(altitude=5.0, duration=20.0), tasks=list(tasks),
                      seed=0, **kw).run()


@pytest.fixture(scope="module")
def hexa_runs():
    """The hexa's blueprint carries a Jetson Orin Nano."""
    return {"none": fly(fa.drone("generic-hexa-680")),
            "own": fly(fa.drone("generic-hexa-680"), [fa.Task(MODEL, period_s=1.0)]),
            "pi": fly(fa.drone("generic-hexa-680"),
                      [fa.Task(MODEL, period_s=1.0, device="raspberry-pi-4")])}


def test_a_task_without_a_device_runs_on_the_drones_computer(hexa_runs):
    assert fa.Task(MODEL).device is None
    own, none = hexa_runs["own"], hexa_runs["none"]
    assert own.scenario["computers"] == [{"name": "jetson-orin-nano", "source": "blueprint"}]
    orin = device("jetson-orin-nano")
    # the task's latency is the Orin's: overhead + MACs / throughput
    assert own.kpis["inference_latency_p50_s"] == pytest.approx(orin.overhead_s + 3e8 / orin.macs_per_s)
    # the ML task costs processing energy, it never saves any
    assert own.kpis["energy_proc_j"] > none.kpis["energy_proc_j"]


def test_a_task_naming_another_computer_adds_and_powers_it(hexa_runs):
    pi_run, none = hexa_runs["pi"], hexa_runs["none"]
    assert pi_run.scenario["computers"] == [
        {"name": "jetson-orin-nano", "source": "blueprint"},
        {"name": "raspberry-pi-4", "source": "added by task 'cnn'"}]
    pi, orin = device("raspberry-pi-4"), device("jetson-orin-nano")
    # before: the Pi replaced the Jetson and the flight drew LESS (589.9 J vs 603.5 J)
    extra = pi_run.kpis["energy_proc_j"] - none.kpis["energy_proc_j"]
    t = pi_run.kpis["flight_time_s"]
    assert extra >= pi.idle_w * t * 0.99                    # at least the Pi idling all along
    assert extra <= pi.active_w * t                          # at most the Pi busy all along
    lat = pi.overhead_s + 3e8 / pi.macs_per_s
    assert pi_run.kpis["inference_latency_p50_s"] == pytest.approx(lat)
    assert orin.idle_w > 0


def test_a_drone_without_a_computer_needs_a_device():
    cf = fa.drone("crazyflie-2-1")
    with pytest.raises(ConfigError, match=r"task 'cnn' runs on the drone's on-board computer, "
                                          r"and crazyflie-2-1 has none .*give the task device="):
        fly(cf, [fa.Task(MODEL, sensor="gps", period_s=1.0)])
    r = fly(fa.drone("crazyflie-2-1"), [fa.Task(MODEL, sensor="gps", period_s=1.0,
                                                  device="raspberry-pi-4")])
    assert r.scenario["computers"] == [{"name": "raspberry-pi-4",
                                        "source": "added by task 'cnn'"}]


def test_tasks_of_one_drone_share_one_computer():
    with pytest.raises(ConfigError, match=r"on-board tasks run on different computers "
                                          r"\(jetson-orin-nano, raspberry-pi-4\)"):
        fly(fa.drone("generic-hexa-680"), [fa.Task(MODEL, name="a"),
                                           fa.Task(MODEL, name="b", device="raspberry-pi-4")])
