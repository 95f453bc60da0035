"""ML in the loop (issue 25): applications whose model's output steers the drone.

Each test is a question an ML team asks before flying, answered with budgets:

- Does a person-following app keep a walker when the shipped detector runs on a
  Raspberry Pi 4, on a Jetson Orin Nano, or on the ground station over Wi-Fi?
- If the detector slows down when the battery runs low, how much flight time is
  gained and how many people are missed?
- Does precision landing on a marker hold in an 8 m/s wind?
- For which target speeds, turns and winds does the follow app break?
- How long do 1, 2 or 4 drones sharing detections through one ground station
  take to find five people walking in a 120 m square?

Flights come from the flight cache on a warm run (the hypothesis search is
derandomized, so it is cached too).
"""

from pathlib import Path

import numpy as np
import pytest
from hypothesis import Phase, given, settings
from hypothesis import strategies as st
from pycocotools import mask as cocomask

import pytest_flockai as fa
from pytest_flockai import cacheable, check_budgets
from pytest_flockai import strategies as fst

MODELS = Path(__file__).resolve().parent.parent / "fixtures" / "models"
CLIMB_S = 12.0


def walker(speed=1.4, turn_deg=90.0):
    """A person who walks 40 m, turns and walks 30 m more (1.4 m/s: Bohannon 1997)."""
    return fa.actors.walk_and_turn(start=(3.0, 0.0), start_s=CLIMB_S, first_m=40.0,
                                   turn_deg=turn_deg, then_m=30.0, speed=speed, name="alice")


def follow_mission(model, *, device=None, execution="onboard", speed=1.4, turn_deg=90.0,
                   wind=None, period_s=0.2):
    task = fa.Task(model, period_s=period_s, evaluate="detection", score_threshold=0.4,
                   execution=execution, name="det")
    drone = fa.drone("dji-mavic-2-pro", **({"device": device} if device else {}))
    return fa.Mission(drone, fa.pilots.Hover(altitude=25.0),
                      world=fa.World.scene(size=(300.0, 300.0)), tasks=[task],
                      actors=[walker(speed, turn_deg)],
                      policies=[fa.policy.Follow("det", score="alice")], wind=wind,
                      until=CLIMB_S + 70.0 / speed + 4.0, seed=0)


@pytest.fixture(scope="session")
def detector():
    return fa.ml.OnnxModel(MODELS / "detector.onnx", name="detector")


FOLLOW = {"pi4": dict(device="raspberry-pi-4"), "orin": dict(device="jetson-orin-nano"),
          "remote": dict(execution="remote")}


@pytest.fixture(scope="session", params=list(FOLLOW))
def follow_flight(request, detector):
    return request.param, follow_mission(detector, **FOLLOW[request.param]).run()


@pytest.mark.kpi(track_error_p95_m="<= 4.5 m", track_lost_count="== 0",
                 time_to_detect_s="<= 2 s", crashed="== 0")
def test_follow_a_walker_with_the_shipped_detector(follow_flight):
    """The detector every 0.2 s at 25 m, the walker turning 90 degrees after 40 m. On the
    Pi 4 each frame takes 13 ms (ONNX Runtime, the layer model of compute.predict_latency;
    0.12 s under the former 1.5 GMAC/s rule), on the Orin 2.1 ms (TensorRT fp16), on the
    ground GPU over Wi-Fi a few ms more for the radio; all three keep the walker within
    4.5 m and never lose her."""
    where, res = follow_flight
    k = res.kpis
    latency = {"pi4": (0.01, 0.02), "orin": (0.0, 0.005), "remote": (0.0, 0.05)}[where]
    assert latency[0] <= k["inference_latency_p50_s"] <= latency[1]
    assert k["det.recall"] >= 0.9


@cacheable     # reads the records only: its flights may come from the flight cache
def people_found(records) -> dict:
    """Distinct people (by world id) whose box some frame's (N, 6) detections covered at
    IoU >= 0.5 (pycocotools' box IoU, as the COCO metrics)."""
    found = set()
    for r in records:
        d = np.asarray(r.prediction if r.prediction is not None else np.zeros((0, 6)), dtype=float)
        gt = np.asarray(r.truth.boxes, dtype=float).reshape(-1, 4)
        if len(d) and len(gt):
            iou = cocomask.iou(_xywh(d[:, :4]), _xywh(gt), [0] * len(gt))
            found.update(int(i) for i, hit in zip(r.truth.ids, (iou >= 0.5).any(axis=0)) if hit)
    return {"people_found": float(len(found))}


def _xywh(boxes):
    """(x1, y1, x2, y2) rows as COCO's (x, y, w, h)."""
    return np.column_stack([boxes[:, :2], boxes[:, 2:4] - boxes[:, :2]])


def survey(policies=()):
    """A 20 m lawnmower over 24 people with the detector's cost on a Pi 4 (an oracle
    charged 165.5 M MACs per frame: no frame is rendered)."""
    task = fa.Task(fa.ml.Oracle(classes=["person"], macs=165_475_200), period_s=0.2,
                   evaluate=people_found, name="eye")
    people = [(x, y) for x in range(-50, 51, 20) for y in range(-30, 31, 20)]
    return fa.Mission(fa.drone("dji-mavic-2-pro", device="raspberry-pi-4"),
                      fa.pilots.ZigZag(area=((-60, -40), (60, 40)), altitude=20.0, spacing=20.0,
                                       speed=6.0),
                      world=fa.World.scene(people=people, size=(200.0, 200.0)), tasks=[task],
                      policies=policies, seed=0)


def test_adaptive_workload_by_battery():
    """Below 97 % battery the detector drops from 5 Hz to one frame in 8 s. The gain is
    the Pi's active power over the rest of the flight, about 1 % of a Mavic's 107 W: the
    projected endurance grows by ~1.2 % (1860 s to 1882 s) and 6 of 24 people are missed
    (the saver takes over at 55 s; with the Mavic's fitted efficiency before session 7:
    1702 s to 1721 s and 4 missed). Budget: at least 0.5 % more endurance, at most 7 people missed."""
    saver = fa.policy.Rule("battery < 0.97", [fa.policy.SetPeriod("eye", 8.0)], name="saver")
    fixed, adaptive = survey().run().kpis, survey([saver]).run().kpis
    gain = adaptive["endurance_s"] / fixed["endurance_s"] - 1.0
    missed = fixed["eye.people_found"] - adaptive["eye.people_found"]
    assert gain >= 0.005, gain
    assert missed <= 7, missed
    assert adaptive["policy.saver.triggers"] == 1


@pytest.mark.kpi(landing_error_m="<= 1 m", crashed="== 0")
def test_marker_landing_in_an_8_mps_wind():
    """OpenCV's ArUco detector on the rendered frames, a 1.5 m tag, descend to 3 m and
    land: 0.46 m off the centre in an 8 m/s Dryden wind (0.06 m in calm air)."""
    task = fa.Task(fa.ml.MarkerDetector(), period_s=0.2, classes=("marker",), name="tag")
    survey = fa.pilots.Waypoints([(0.0, 0.0, 12.0), (20.0, 0.0, 12.0), (20.0, 20.0, 12.0)],
                                 speed=3.0)
    res = fa.Mission(fa.drone("dji-mavic-2-pro"), survey, world=fa.World.scene(size=(100.0, 100.0)),
                     tasks=[task], actors=[fa.actors.Marker(14.0, 9.0, yaw_deg=30.0)],
                     policies=[fa.policy.MarkerLanding("tag")], wind=8.0, until=120.0).run()
    assert res.end_reason == "landed"


@pytest.mark.flockai_cache("readwrite")   # derandomized: the same flights each run
def test_the_search_finds_where_following_breaks():
    """Hypothesis looks for the target speed, turn and wind that break the follow app's
    budget (oracle boxes every 0.2 s, within 4 m at the 95th percentile, never lost): a
    walker at 1.4 m/s is kept (2.4 m through a 90 degree turn, 3.1 m in a
    10 m/s wind), a jogger who turns sharply is not (3 m/s and 90 degrees: 6.5 m; 180
    degrees loses the track). The failure printed names the speed and turn. Shrinking
    is left out: it flew 40 more flights (5 min) to move the boundary by a few tenths."""
    @settings(max_examples=10, deadline=None, database=None, derandomize=True,
              phases=[Phase.generate])
    @given(speed=st.floats(1.0, 4.0), turn=st.floats(0.0, 180.0), wind=st.floats(0.0, 10.0))
    def following_holds(speed, turn, wind):
        res = follow_mission(fa.ml.Oracle(classes=["person"]), speed=speed, turn_deg=turn,
                             wind=wind or None).run()
        fst.target_margin(res, track_error_p95_m="<= 4 m")
        check_budgets(res, track_error_p95_m="<= 4 m", track_lost_count="== 0")
    with pytest.raises(AssertionError, match="track_"):
        following_holds()


def search_fleet(n: int) -> fa.Fleet:
    area = ((-60.0, -60.0), (60.0, 60.0))
    people = fa.actors.walkers(5, ((-55.0, -55.0), (55.0, 55.0)), seed=4)
    station = fa.policy.GroundStation((0.0, 0.0, 0.0))
    drones = []
    for i, (pilot, pad) in enumerate(fa.fleet.survey(area, n, altitude=20.0, spacing=15.0,
                                                     speed=6.0)):
        eye = fa.Task(fa.ml.Oracle(classes=["person"]), period_s=0.5, evaluate="detection",
                      name="eye")
        drones.append(fa.FleetDrone(f"d{i + 1}", fa.drone("dji-mavic-2-pro"), pilot, pad=pad,
                                    tasks=[eye], seed=i,
                                    policies=[fa.policy.SharedSearch("eye", station, orbit_s=10.0)]))
    return fa.Fleet(drones, world=fa.World.scene(size=(140.0, 140.0)), actors=people)


@pytest.mark.parametrize("n, budget", [(1, None), (2, "<= 200 s"), (4, "<= 120 s")])
def test_a_fleet_finds_five_walkers(n, budget, request):
    """Measured: one drone confirms 4 of the 5 before its survey ends (one walked out of
    its strips' way); two find all five in 171 s, four in 100 s. Every new detection is
    sent to the ground station, which sends the nearest free drone to orbit and confirm
    it (walkers move on, so one walker may be reported and confirmed more than once)."""
    if budget is not None:
        request.node.add_marker(pytest.mark.kpi({"fleet.time_to_find_all_s": budget,
                                                 "fleet.targets_found": "== 5"}))
    res = search_fleet(n).run()
    assert res.kpis["fleet.targets_found"] >= 4
