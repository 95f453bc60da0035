"""Follow with old results, and false positives.

- Results delivered late (inference, queueing, the link) are fused at their capture time
  and predicted to now; the lost timer counts from delivery, so boxes every 0.2 s
  delivered 2.9 s after capture (``lost_after_s`` = 3 s) still lock on. Results older
  than ``lost_after_s`` cannot hold a track: an event says so and ``track_rejected_stale``
  counts them (before: no event, a result indistinguishable from a blind detector).
- A track faster than its class can move (a box stuck at one pixel moves with the drone)
  is dropped: ``track_rejected_implausible``."""

import math

import pytest

import pytest_flockai as fa
from pytest_flockai.policy.follow import MAX_SPEED_MPS


def follow_walker(delay_s, until=40.0):
    alice = fa.actors.walk_and_turn(start=(3.0, 0.0), start_s=12.0, first_m=40.0,
                                    turn_deg=90.0, then_m=20.0, name="alice")
    eye = fa.Task(fa.ml.Oracle(classes=["person"], delay_s=delay_s), period_s=0.2,
                  evaluate="detection", name="eye")
    follow = fa.policy.Follow("eye", target="person", lost_after_s=3.0, score="alice")
    return fa.Mission(fa.drone("dji-mavic-2-pro"), fa.pilots.Hover(altitude=20.0),
                      world=fa.World.scene(size=(200.0, 200.0)), tasks=[eye], actors=[alice],
                      policies=[follow], until=until).run()


def test_results_delivered_just_under_lost_after_s_still_lock_on():
    r = follow_walker(2.9)
    modes = [e["mode"] for e in r.events if e["kind"] == "policy_mode"]
    assert "follow" in modes
    assert math.isfinite(r.kpis["time_to_detect_s"]) and r.kpis["time_to_detect_s"] < 4.0
    assert r.kpis["track_lost_count"] == 0
    assert r.kpis["track_rejected_stale"] == 0
    # predicted at constant velocity over the 2.9 s: the error stays bounded (the turn costs most)
    assert r.kpis["track_error_p95_m"] < 10.0


def test_results_older_than_lost_after_s_are_refused_with_an_event_and_a_kpi():
    r = follow_walker(3.5, until=25.0)
    rejected = [e for e in r.events if e["kind"] == "track_rejected"]
    assert rejected and rejected[0]["reason"] == "stale"
    assert rejected[0]["age_s"] == pytest.approx(3.5, abs=0.05)
    assert rejected[0]["max_age_s"] == 3.0 and "lost_after_s" in rejected[0]["why"]
    assert r.kpis["track_rejected_stale"] >= 10
    assert math.isnan(r.kpis["time_to_detect_s"])


def test_the_speed_limits_are_a_runner_and_a_limited_car():
    assert 10.0 < MAX_SPEED_MPS["person"] < 10.5          # 100 m in 9.58 s
    assert MAX_SPEED_MPS["vehicle"] == pytest.approx(69.44, abs=0.01)   # 250 km/h
