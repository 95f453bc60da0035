"""Fleets: several drones in one MuJoCo model on one clock."""

import math

import numpy as np
import pytest

import pytest_flockai as fa
from pytest_flockai.errors import ConfigError
from pytest_flockai.ml.events import SharedGround

MAVIC = "dji-mavic-2-pro"


def crossing(alt_b: float, speed: float = 6.0) -> fa.Fleet:
    """Two drones whose legs cross at the origin at the same moment: A flies west to
    east along y = 0 at 20 m, B south to north along x = 0 at ``alt_b``. B climbs
    (alt_b - 20) m more at 2 m/s, so its pad is that much flight time closer."""
    a = fa.pilots.Waypoints([(-40, 0, 20), (40, 0, 20)], speed=speed)
    y0 = -40 + (alt_b - 20) / 2.0 * speed
    b = fa.pilots.Waypoints([(0, y0, alt_b), (0, 40, alt_b)], speed=speed)
    return fa.Fleet([fa.FleetDrone("a", fa.drone(MAVIC), a, pad=(-40, 0), seed=1),
                     fa.FleetDrone("b", fa.drone(MAVIC), b, pad=(0, y0), seed=2)],
                    max_time_s=300.0)


def test_crossing_paths_at_one_altitude_collide():
    r = crossing(20.0).run()
    assert r.kpis["a.crashed"] == 1.0 and r.kpis["b.crashed"] == 1.0
    assert r.kpis["fleet.crashes"] == 2.0
    crashes = [e for e in r.events if e["kind"] == "crash"]
    assert {e["drone"] for e in crashes} == {"a", "b"}
    assert all(e["against"] == "drone" for e in crashes)
    assert abs(crashes[0]["t"] - crashes[1]["t"]) < 1e-9          # one contact, one moment
    # they met near the crossing point, in the air
    row = r.telemetry[r.telemetry["drone"] == "a"].iloc[-1]
    assert math.hypot(row["x"], row["y"]) < 2.0 and row["z"] > 15.0


def test_crossing_paths_separated_in_altitude_do_not_collide():
    r = crossing(26.0).run()
    assert r.kpis["a.crashed"] == 0.0 and r.kpis["b.crashed"] == 0.0
    assert r.drones["a"].end_reason == r.drones["b"].end_reason == "landed"
    assert 5.0 < r.kpis["fleet.min_separation_m"] < 7.0           # 6 m apart when they cross


def small_fleet(seed0: int = 0) -> fa.Fleet:
    area = ((0, 0), (60, 60))
    parts = fa.fleet.survey(area, 2, altitude=12, spacing=20, speed=8)
    return fa.Fleet([fa.FleetDrone(f"drone-{i + 1}", fa.drone(MAVIC), p, pad=pad, seed=seed0 + i)
                     for i, (p, pad) in enumerate(parts)], area=area, swath_m=20)


def test_kpis_per_drone_and_fleet_wide_and_a_drone_column():
    r = small_fleet().run()
    assert isinstance(r, fa.FleetResult) and r.end_reason == "landed"
    for name in ("drone-1", "drone-2"):
        assert r.kpis[f"{name}.flight_time_s"] == r.drones[name].kpis["flight_time_s"] > 0
        tel = r.telemetry[r.telemetry["drone"] == name]
        # each lands back on its own pad
        assert tel["x"].iloc[-1] == pytest.approx(r.scenario["fleet"][int(name[-1]) - 1]["pad"][0],
                                                  abs=0.5)
        assert tel["y"].iloc[-1] == pytest.approx(r.scenario["fleet"][int(name[-1]) - 1]["pad"][1],
                                                  abs=0.5)
    assert set(r.telemetry["drone"]) == {"drone-1", "drone-2"}
    assert r.kpis["fleet.makespan_s"] == pytest.approx(
        max(r.drones[n].sim_time_s for n in r.drones))
    assert r.kpis["fleet.coverage_fraction"] > 0.95
    assert r.kpis["fleet.crashes"] == 0.0
    assert r.kpis["fleet.min_separation_m"] >= 15.0                # strips 20+ m apart
    assert r.kpis["fleet.energy_total_j"] == pytest.approx(
        sum(r.drones[n].kpis["energy_total_j"] for n in r.drones))


def test_same_seeds_same_fleet_kpis():
    a, b = small_fleet().run(), small_fleet().run()
    assert a.kpis == b.kpis
    assert np.array_equal(a.telemetry[["x", "y", "z"]].to_numpy(), b.telemetry[["x", "y", "z"]].to_numpy())


def test_a_fleet_of_one_flies_like_the_same_single_mission():
    """The drones of a fleet run the single flight's components: one drone at the
    origin gives the single Mission's KPIs."""
    pilot = fa.pilots.Waypoints([(0, 0, 10), (30, 0, 10)], speed=5)
    single = fa.Mission(fa.drone(MAVIC), pilot, seed=3).run()
    fleet = fa.Fleet([fa.FleetDrone("solo", fa.drone(MAVIC), pilot, pad=(0, 0), seed=3)]).run()
    for k in ("flight_time_s", "distance_m", "energy_total_j", "tracking_error_max_m"):
        assert fleet.kpis[f"solo.{k}"] == pytest.approx(single.kpis[k], rel=1e-9), k


def test_strips_split_the_legs_of_one_zigzag():
    one = fa.pilots.ZigZag(((0, 0), (100, 150)), spacing=25)
    parts = fa.fleet.strips(((0, 0), (100, 150)), 3, 25)
    rows = sorted({p[1] for p in one.points})
    got = sorted({p[1] for sub in parts
                  for p in fa.pilots.ZigZag(sub, spacing=25).points})
    assert got == rows                                            # the same legs, shared out
    assert [sub[0][1] for sub in parts] == [0.0, 75.0, 125.0]           # 7 legs: 3, 2, 2


@pytest.mark.slow
def test_four_drones_cover_an_area_in_a_quarter_of_one_drones_time():
    area = ((0, 0), (300, 375))                                   # 16 legs of 300 m, 25 m apart

    def fly(n):
        parts = fa.fleet.survey(area, n, altitude=30, spacing=25, speed=8)
        return fa.Fleet([fa.FleetDrone(f"d{i}", fa.drone(MAVIC), p, pad=pad, seed=i)
                         for i, (p, pad) in enumerate(parts)], area=area, swath_m=25).run()
    one, four = fly(1), fly(4)
    assert one.kpis["fleet.coverage_fraction"] > 0.99 and four.kpis["fleet.coverage_fraction"] > 0.99
    ratio = four.kpis["fleet.coverage_time_s"] / one.kpis["fleet.coverage_time_s"]
    print(f"coverage time: 1 drone {one.kpis['fleet.coverage_time_s']:.0f} s, 4 drones "
          f"{four.kpis['fleet.coverage_time_s']:.0f} s, ratio {ratio:.3f}; makespan ratio "
          f"{four.kpis['fleet.makespan_s'] / one.kpis['fleet.makespan_s']:.3f}")
    assert 0.25 * 0.85 <= ratio <= 0.25 * 1.15
    assert four.kpis["fleet.crashes"] == 0.0


@pytest.mark.parametrize("make, match", [
    (lambda d, p: fa.Fleet([]), r"drones = \[\] is empty; allowed: 1 to"),
    (lambda d, p: fa.Fleet([fa.FleetDrone("x", d, p, pad=(0, 0)),
                            fa.FleetDrone("x", d, p, pad=(10, 0))]),
     r"drones\[1\].name = 'x' is also drones\[0\].name; allowed: a unique name"),
    (lambda d, p: fa.Fleet([fa.FleetDrone("x", d, p, pad=(0, 0)),
                            fa.FleetDrone("y", d, p, pad=(0.5, 0))]),
     r"drones\[1\].pad = \(0.5, 0.0\).*two drones at one pad; allowed: pads at least 2 m apart"),
    (lambda d, p: fa.Fleet(["x"]), r"drones\[0\] = 'x' is not a fa.FleetDrone"),
    (lambda d, p: fa.FleetDrone("a.b", d, p), r"name = 'a.b' is not allowed"),
    (lambda d, p: fa.FleetDrone("a", "mavic", p), r"drone = 'mavic' is not a Drone"),
    (lambda d, p: fa.FleetDrone("a", d, p, pad=(0, 0, 0)), r"pad"),
    (lambda d, p: fa.Fleet([fa.FleetDrone("a", d, p)], area=((0, 0), (1, 1))),
     r"area = .* and swath_m = None: give both"),
    (lambda d, p: fa.fleet.survey(((0, 0), (100, 50)), 3, spacing=25), r"n <= 1"),
    (lambda d, p: fa.Fleet([fa.FleetDrone("a", d, p), fa.FleetDrone("b", fa.drone("crazyflie-2-1"),
                                                                     p, pad=(5, 0))]),
     r"the drones' \[sim\] rates differ .*allowed: one physics_hz and control_hz"),
    (lambda d, p: fa.FleetDrone("a", d, p, tasks=[object()]),
     r"FleetDrone 'a': Mission: tasks\[0\] = .* is not a Task"),
    (lambda d, p: fa.FleetDrone("a", d, p, tasks=[fa.Task(_model(), sensor="gps")]),
     r"task 'cnn' reads sensor = 'gps'; in a fleet a task reads the drone's camera only"),
    (lambda d, p: fa.Fleet([fa.FleetDrone("a", d, p, tasks=[_task("remote")]),
                            fa.FleetDrone("b", d, p, pad=(5, 0),
                                          tasks=[_task("remote", link="sik-915")])]),
     r"the remote tasks' link differ .*allowed: one link for the fleet's one ground station"),
    (lambda d, p: fa.Fleet([fa.FleetDrone("a", d, p, tasks=[_task("remote")])],
                           offload=fa.fleet.Offload()),
     r"offload = .* and remote tasks \('a': 'cnn'\) together are not supported"),
    (lambda d, p: fa.Fleet([fa.FleetDrone("a", d, p)], shared_link="yes"),
     r"shared_link = 'yes' is not allowed"),
])
def test_bad_fleets_raise_config_errors(make, match):
    with pytest.raises(ConfigError, match=match):
        make(fa.drone(MAVIC), fa.pilots.Hover(5, 1))


def test_budgets_on_fleet_kpis_in_pytest(pytester):
    pytester.makepyfile(test_fleet_budgets='''
import pytest
import pytest_flockai as fa


def fleet():
    a = fa.pilots.Hover(altitude=2.0, duration=2.0)
    b = fa.pilots.Hover(altitude=3.0, duration=2.0)
    return fa.Fleet([fa.FleetDrone("drone-1", fa.drone("crazyflie-2-1"), a, pad=(0, 0)),
                     fa.FleetDrone("drone-2", fa.drone("crazyflie-2-1"), b, pad=(4, 0))])


@pytest.mark.kpi({"fleet.min_separation_m": ">= 3 m", "drone-2.flight_time_s": ">= 2 s",
                  "fleet.crashes": "== 0"})
def test_kept():
    fleet().run()


@pytest.mark.kpi({"fleet.makespan_s": "<= 1 s", "drone-1.crashed": "== 0"})
def test_broken():
    fleet().run()
''')
    res = pytester.runpytest_inprocess("-p", "no:cacheprovider")
    res.assert_outcomes(passed=1, failed=1)
    res.stdout.fnmatch_lines(["*1 of 2 KPI budget(s) broken in test_fleet_budgets.py::test_broken*",
                              "*fleet.makespan_s*<= 1 s*BROKEN*"])


@pytest.mark.parametrize("ext", ["csv", "jsonl"])
def test_a_fleet_result_saves_and_loads_with_its_drone_column(tmp_path, ext):
    a, b = fa.pilots.Hover(2.0, 1.0), fa.pilots.Hover(3.0, 1.0)
    r = fa.Fleet([fa.FleetDrone("d1", fa.drone("crazyflie-2-1"), a),
                  fa.FleetDrone("d2", fa.drone("crazyflie-2-1"), b, pad=(4, 0))]).run()
    back = fa.FlightResult.load(r.save(tmp_path / f"fleet.{ext}"))
    assert back.kpis == r.kpis
    assert list(back.telemetry["drone"]) == list(r.telemetry["drone"])
    assert np.array_equal(back.telemetry["z"].to_numpy(), r.telemetry["z"].to_numpy())


def offload_fleet(n: int, shared: bool, macs: float = 8.7e9) -> fa.FleetResult:
    """``n`` Mavics hovering 10 m up on a line, 60-70+ m from the ground station,
    each sending a 150 kB frame every 0.5 s over 802.11n."""
    off = fa.fleet.Offload(period_s=0.5, frame_bytes=150_000, shared_link=shared, macs=macs,
                           ground_station=(0, -60, 1))
    return fa.Fleet([fa.FleetDrone(f"d{i}", fa.drone(MAVIC), fa.pilots.Hover(10, 10),
                                   pad=(10 * i, 0), seed=i) for i in range(n)], offload=off).run()


def test_offload_latency_grows_with_the_fleet_on_a_shared_link_and_not_on_own_links():
    sizes = (1, 2, 4, 8)
    shared = {n: offload_fleet(n, True).kpis for n in sizes}
    own = {n: offload_fleet(n, False).kpis for n in (1, 8)}
    print("offload latency p95 (s), shared link: " + ", ".join(
        f"{n} drones {shared[n]['offload.latency_p95_s']:.3f}" for n in sizes)
        + f"; own links: 1 drone {own[1]['offload.latency_p95_s']:.3f}, "
          f"8 drones {own[8]['offload.latency_p95_s']:.3f}")
    p95 = [shared[n]["offload.latency_p95_s"] for n in sizes]
    assert all(a < b for a, b in zip(p95, p95[1:]))
    assert p95[-1] > 4 * p95[0]
    assert shared[8]["link.queue_delay_p95_s"] > 0.1 and shared[1]["link.queue_delay_p95_s"] == 0
    assert own[8]["offload.latency_p95_s"] < 1.6 * own[1]["offload.latency_p95_s"]
    assert own[8]["link.queue_delay_p95_s"] == 0.0
    for k in (shared[8], own[8]):
        assert k["d0.offload.frames"] == k["d7.offload.frames"] > 15       # every frame answered


def test_a_slow_ground_device_queues_the_fleet():
    """0.2 s per inference on the ground GPU (1e12 MACs at 5 TMAC/s), frames every 0.5 s:
    two drones fit, four saturate it."""
    two, four = offload_fleet(2, False, 1e12).kpis, offload_fleet(4, False, 1e12).kpis
    assert two["ground.queue_delay_mean_s"] < 0.2 < four["ground.queue_delay_mean_s"]
    busy = sum(four[f"d{i}.offload.frames"] for i in range(4)) * (0.002 + 0.2)
    assert four["ground.utilization"] == pytest.approx(min(1.0, busy / four["fleet.makespan_s"]))
    assert four["ground.utilization"] > 1.8 * two["ground.utilization"]


def test_bad_offload():
    with pytest.raises(ConfigError, match=r"Offload: frame_bytes = 0 is not allowed"):
        fa.fleet.Offload(frame_bytes=0)
    with pytest.raises(ConfigError, match=r"link = 'wifi-6' is not a known link"):
        fa.fleet.Offload(link="wifi-6")
    with pytest.raises(ConfigError, match=r"Fleet: offload = 3 is not allowed"):
        fa.Fleet([fa.FleetDrone("a", fa.drone(MAVIC), fa.pilots.Hover(5, 1))], offload=3)


# -- ML tasks and cameras on fleet drones -----------------------------------------------

def _bright(frame):
    """A real (if simple) model: the mean brightness of the drone's own rendered frame."""
    return float(np.asarray(frame).mean())


def _model(macs=1e9):
    return fa.ml.PythonModel(_bright, macs=macs, name="cnn")


def _task(execution, period_s=0.5, **kw):
    kw.setdefault("ground_station", (0, -20, 1))
    kw.setdefault("crowd_threshold", 1000.0)                 # no alert frames
    return fa.Task(_model(kw.pop("macs", 1e9)), period_s=period_s, execution=execution, **kw)


def camera_fleet(n, execution="remote", shared_link=True, **task):
    """``n`` Mavics with a small camera (64 x 48) hovering 15 m up over the city, 25 m apart,
    each running its own camera task every 0.5 s."""
    world = fa.World.urban(seed=3, size=(160.0, 160.0), people=40, max_building_height=10.0)
    mavic = fa.drone(MAVIC, width=64, height=48)
    return fa.Fleet([fa.FleetDrone(f"drone-{i + 1}", mavic, fa.pilots.Hover(15, 6),
                                   pad=(25 * i - 40, 10), seed=i, tasks=[_task(execution, **task)])
                     for i in range(n)], world=world, shared_link=shared_link).run()


def test_two_drones_with_camera_tasks_get_their_own_latency_and_evaluation_kpis():
    r = camera_fleet(2, "onboard", macs=5e8)
    preds = {}
    for name in ("drone-1", "drone-2"):
        k = {key[len(name) + 1:]: v for key, v in r.kpis.items() if key.startswith(name + ".")}
        assert k["cnn.inference_count"] >= 10
        assert 0 < k["cnn.inference_latency_p95_s"] == k["inference_latency_p95_s"] < 0.5
        assert "cnn.count_mae" in k                   # the task's evaluation against the truth
        assert k["cpu_time_s"] > 0                   # the on-board computer was busy
        preds[name] = [e["count"] for e in r.events if e["kind"] == "inference"
                       and e["drone"] == name]
    # each drone renders its own view of the shared world: they see different ground
    assert preds["drone-1"] != preds["drone-2"]
    assert r.kpis["fleet.inference_latency_p95_s"] > 0


@pytest.mark.slow
def test_remote_task_latency_grows_with_the_fleet_on_a_shared_link():
    """64 kbit/s telemetry radio: a 64 x 48 JPEG takes ~0.3 s of airtime, frames every
    0.5 s, so four drones sharing the channel queue for it; on their own channels they
    do not (the ground GPU is shared in both, and fast)."""
    shared = {n: camera_fleet(n, link="sik-915").kpis for n in (1, 4)}
    own4 = camera_fleet(4, link="sik-915", shared_link=False).kpis
    p1, p4 = (shared[n]["fleet.inference_latency_p95_s"] for n in (1, 4))
    print(f"remote task p95 on a shared 64 kbit/s link: 1 drone {p1:.3f} s, 4 drones {p4:.3f} s;"
          f" 4 drones on their own links {own4['fleet.inference_latency_p95_s']:.3f} s")
    assert p4 > 1.5 * p1
    for i in range(1, 5):
        assert own4[f"drone-{i}.cnn.inference_latency_p95_s"] > 0
    assert shared[4]["link.queue_delay_p95_s"] > 0.1 and shared[1]["link.queue_delay_p95_s"] == 0
    assert own4["link.queue_delay_p95_s"] == 0.0
    assert own4["fleet.inference_latency_p95_s"] < 1.2 * p1
    assert 0 < shared[4]["ground.utilization"] < 0.1


def test_camera_fleets_are_deterministic():
    a, b = camera_fleet(2, link="sik-915").kpis, camera_fleet(2, link="sik-915").kpis
    assert a == b and a["drone-2.cnn.inference_count"] > 0


def test_shared_ground_is_one_fifo_channel_and_one_fifo_device():
    g = SharedGround(shared_link=True)
    assert g.uplink(0, 1.0, 0.3) == 1.0 and g.uplink(1, 1.0, 0.3) == pytest.approx(1.3)
    assert g.uplink(1, 5.0, 0.3) == 5.0                       # the channel was free again
    assert g.compute(1.3, 0.1) == 1.3 and g.compute(1.35, 0.1) == pytest.approx(1.4)
    assert g.link_wait == pytest.approx([0.0, 0.3, 0.0]) and g.busy_s == pytest.approx(0.2)
    own = SharedGround(shared_link=False)                     # a channel per drone
    assert own.uplink(0, 1.0, 0.3) == 1.0 and own.uplink(1, 1.0, 0.3) == 1.0


def test_a_fleet_of_one_with_a_remote_camera_task_flies_like_the_single_mission():
    """The same scheduler, camera and runner as a single flight: one drone alone on the
    ground station gives the single Mission's KPIs, task KPIs included, exactly."""
    world = fa.World.urban(seed=3, size=(160.0, 160.0), people=40, max_building_height=10.0)
    mavic = fa.drone(MAVIC, width=64, height=48)
    pilot = fa.pilots.Waypoints([(0, 0, 15), (20, 0, 15)], speed=5)
    single = fa.Mission(mavic, pilot, world=world, tasks=[_task("remote", link="sik-915")], seed=3).run()
    fleet = fa.Fleet([fa.FleetDrone("solo", mavic, pilot, pad=(0, 0), seed=3,
                                    tasks=[_task("remote", link="sik-915")])], world=world).run()
    assert single.kpis["cnn.inference_count"] > 20
    for k, v in single.kpis.items():
        w = fleet.kpis[f"solo.{k}"]
        assert v == w or (math.isnan(v) and math.isnan(w)), k
