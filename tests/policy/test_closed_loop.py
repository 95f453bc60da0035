"""The closed loop is honest: a follow pilot decides only from task results as they
are delivered, flown against a person walking at 1.4 m/s who walks 60 m and turns.

Budgets stated here (oracle boxes every 0.2 s, drone at 20 m, Mavic 2 Pro):
the follower keeps the walker within 3 m at the 95th percentile, the error
measured from the drone's true position to the walker's true position.
"""

import math

import cv2
import numpy as np
import pytest

import pytest_flockai as fa
from pytest_flockai.cache.key import flight_key

BUDGET_P95_M = 3.0


def walker():
    return fa.actors.walk_and_turn(start=(3.0, 0.0), start_s=12.0, first_m=60.0, turn_deg=90.0,
                                   then_m=40.0, name="alice")


def follow_mission(model=None, *, delay_s=0.0, cut_at=None, on_lost="hold", seed=0, until=80.0,
                   period_s=0.2):
    model = model if model is not None else fa.ml.Oracle(classes=["person"], delay_s=delay_s)
    task = fa.Task(model, period_s=period_s, evaluate="detection", name="eye")
    policies = [fa.policy.Follow("eye", score="alice", on_lost=on_lost)]
    if cut_at is not None:          # the detections stop: the task is switched off
        policies.append(fa.policy.Rule(f"time_s >= {cut_at}", [fa.policy.DisableTask("eye")],
                                       name="cut", period_s=0.1))
    return fa.Mission(fa.drone("dji-mavic-2-pro"), fa.pilots.Hover(altitude=20.0),
                      world=fa.World.scene(size=(300.0, 300.0)), tasks=[task], actors=[walker()],
                      policies=policies, until=until, seed=seed)


def policy_events(res, action=None):
    return [e for e in res.events if e["kind"] == "policy"
            and (action is None or e["action"] == action)]


@pytest.fixture(scope="module")
def prompt():
    return follow_mission(delay_s=0.01).run()


def test_oracle_follow_keeps_a_walker_within_budget(prompt):
    k = prompt.kpis
    assert k["track_error_p95_m"] <= BUDGET_P95_M
    assert k["track_lost_count"] == 0
    assert k["policy.follow.time_follow_s"] > 60.0        # from the first frames to the end
    assert k["time_to_detect_s"] < 1.0
    assert [e["action"] for e in policy_events(prompt)] == ["follow"]


def test_detections_cut_off_lose_the_track_and_run_the_fallback():
    res = follow_mission(delay_s=0.01, cut_at=30.0).run()
    k = res.kpis
    assert k["track_lost_count"] == 1
    off = policy_events(res, "disable")[0]
    lost = policy_events(res, "track_lost")[0]
    hold = policy_events(res, "hold")[0]
    assert 30.0 <= off["t"] < 30.2
    # lost after lost_after_s (3 s) without a delivered detection, then the fallback
    assert 32.8 <= lost["t"] <= 33.5 and lost["fallback"] == "hold"
    assert hold["t"] == lost["t"]
    assert k["track_lost_s"] == pytest.approx(res.kpis["flight_time_s"] - lost["t"], abs=0.2)
    # the drone holds where it was while the walker walks on: it is far from her at the end
    x, y = res.telemetry[["x", "y"]].iloc[-1]
    assert math.dist((x, y), walker().at(80.0)[:2]) > 20.0


def test_late_boxes_grow_the_track_error_by_speed_times_delay(prompt):
    """The same perfect boxes, 1 s late instead of 10 ms. The tracker fuses each box at
    its capture time and predicts to now, so on the straight legs the lag is taken out;
    at the turn it extrapolates the old heading until boxes captured after the turn
    arrive, 0.99 s later than before: the worst errors grow by about walking speed x
    extra delay = 1.4 m/s x 0.99 s = 1.39 m (measured 1.50 m)."""
    late = follow_mission(delay_s=1.0).run()
    assert late.kpis["inference_latency_p50_s"] == pytest.approx(
        prompt.kpis["inference_latency_p50_s"] + 0.99, abs=1e-6)
    growth = late.kpis["track_error_p95_m"] - prompt.kpis["track_error_p95_m"]
    assert 0.7 <= growth <= 2.1, growth
    assert late.kpis["track_error_mean_m"] > prompt.kpis["track_error_mean_m"]


def test_a_detector_that_sees_nothing_never_follows():
    """A real model, run on rendered frames, that finds nothing: the truth of every
    frame holds the walker, and none of it may reach the decision."""
    blind = fa.ml.PythonModel(lambda frame: np.zeros((0, 6)), macs=0, name="blind")
    res = follow_mission(blind, until=40.0, period_s=0.5).run()
    assert res.kpis["eye.recall"] == 0.0            # the walker was in view: truth had her
    assert policy_events(res) == []
    assert res.kpis["policy.follow.time_follow_s"] == 0.0
    assert math.isnan(res.kpis["track_error_p95_m"])
    assert math.isnan(res.kpis["time_to_detect_s"])


def test_an_oracle_renders_no_frame():
    seen = {}

    class Spy(fa.Clocked):
        def bind(self, run):
            super().bind(run)
            seen["camera"] = run.suite["camera"]

        def step(self, t):
            pass

    m = follow_mission(until=20.0)
    res = m.replace(components=[*m.components, Spy()]).run()
    assert res.kpis["eye.inference_count"] > 20
    assert seen["camera"].frames == 0


@pytest.mark.flockai_cache("off")
def test_same_seed_same_closed_loop():
    noisy = dict(classes=["person"], miss_rate=0.3, box_noise_px=3.0, false_positives=0.5)
    a = follow_mission(fa.ml.Oracle(**noisy), until=40.0, seed=3).run().kpis
    b = follow_mission(fa.ml.Oracle(**noisy), until=40.0, seed=3).run().kpis
    c = follow_mission(fa.ml.Oracle(**noisy), until=40.0, seed=4).run().kpis
    keys = ["track_error_p95_m", "track_error_mean_m", "eye.recall", "distance_m"]
    assert [a[k] for k in keys] == [b[k] for k in keys]
    assert [a[k] for k in keys] != [c[k] for k in keys]


def test_flight_cache_keys_include_policies_and_actors():
    base = flight_key(follow_mission())
    assert flight_key(follow_mission()) == base
    assert flight_key(follow_mission(on_lost="land")) != base
    assert flight_key(follow_mission(delay_s=0.5)) != base
    other = follow_mission().replace(actors=(fa.actors.walk_and_turn(
        start=(3.0, 0.0), start_s=12.0, turn_deg=-90.0, name="alice"),))
    assert flight_key(other) != base


def red_tops(frame):
    """A real, pixel-reading detector: the walking figure's red top by an HSV threshold,
    one box per blob (OpenCV)."""
    hsv = cv2.cvtColor(np.asarray(frame), cv2.COLOR_RGB2HSV)
    mask = (cv2.inRange(hsv, (0, 120, 80), (8, 255, 255))
            | cv2.inRange(hsv, (172, 120, 80), (180, 255, 255)))
    _, _, stats, _ = cv2.connectedComponentsWithStats(mask)
    rows = [(x, y, x + w, y + h, 0.9, 0) for x, y, w, h, a in stats[1:] if a >= 3]
    return np.asarray(rows, float).reshape(-1, 6)


@pytest.mark.slow
def test_a_slow_radio_degrades_the_loop():
    """The frames go to the ground station and the boxes come back: over 802.11n a frame's
    round trip takes 8 ms; over a 64 kbit/s SiK telemetry radio the JPEG takes ~0.7 s,
    three frames in four are dropped while one is in flight, the first confirmed track
    comes 1.2 s later and the 95th-percentile error grows from 2.6 m to 4.1 m (measured)."""
    model = fa.ml.OpenCVModel(red_tops, macs=30 * 320 * 240, name="red")

    def over(link):
        task = fa.Task(model, period_s=0.2, execution="remote", link=link, evaluate="detection",
                       name="eye")
        alice = fa.actors.walk_and_turn(start=(3.0, 0.0), start_s=12.0, first_m=40.0,
                                        turn_deg=90.0, then_m=20.0, name="alice")
        return fa.Mission(fa.drone("dji-mavic-2-pro"), fa.pilots.Hover(altitude=20.0),
                          world=fa.World.scene(size=(200.0, 200.0)), tasks=[task],
                          actors=[alice], policies=[fa.policy.Follow("eye", score="alice")],
                          until=55.0).run().kpis

    wifi, sik = over("wifi-80211n"), over("sik-915")
    assert wifi["inference_latency_p50_s"] < 0.05 < 0.5 < sik["inference_latency_p50_s"]
    assert sik["frames_dropped"] > 0.5 * sik["eye.inference_count"] + wifi["frames_dropped"]
    assert sik["time_to_detect_s"] > wifi["time_to_detect_s"] + 0.5
    assert sik["track_error_p95_m"] > wifi["track_error_p95_m"] + 1.0
