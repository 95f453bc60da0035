"""A geofence (the world's bounds by default, or a polygon and a ceiling) with
a PX4-like breach action; goto/orbit targets outside the world refused; a false
positive stuck at one pixel no longer flies the drone out of the world."""


import numpy as np
import pytest

import pytest_flockai as fa
from pytest_flockai.errors import ConfigError
from pytest_flockai.policy.geofence import inside

WORLD = 200.0          # a 200 m square: the fence is +-100 m


class Scripted(fa.Policy):
    def __init__(self, script, **kw):
        super().__init__(**kw)
        self.script = script

    def start(self, run):
        self.done = set()
        self.answers = []

    def decide(self, t, drone):
        for i, (at, fn) in enumerate(self.script):
            if t >= at and i not in self.done:
                self.done.add(i)
                self.answers.append(fn(drone))


def fly(pilot, policies, until=60.0, tasks=(), actors=()):
    return fa.Mission(fa.drone("dji-mavic-2-pro"), pilot, world=fa.World.scene(size=(WORLD, WORLD)),
                      policies=policies, tasks=list(tasks), actors=list(actors), until=until).run()


def farthest(res):
    return float(np.abs(res.telemetry[["x", "y"]].to_numpy()).max())


def test_goto_and_orbit_outside_the_world_are_refused():
    pol = Scripted([(15.0, lambda d: d.goto(5000.0, 0.0)),
                    (16.0, lambda d: d.orbit(95.0, 0.0, radius=10.0)),
                    (17.0, lambda d: d.goto(40.0, 0.0))])
    res = fly(fa.pilots.Hover(altitude=15.0), [pol], until=40.0)
    refused = [e for e in res.events if e["kind"] == "policy_refused"]
    assert [e["action"] for e in refused] == ["goto", "orbit"]
    assert "(5000, 0) is outside the world" in refused[0]["reason"]
    assert "outside the world" in refused[1]["reason"]
    assert [e["action"] for e in res.events if e["kind"] == "policy"] == ["goto"]
    assert farthest(res) < 45.0


def test_a_plan_leaving_the_world_is_held_at_the_fence():
    plan = fa.pilots.Waypoints([(0.0, 0.0, 15.0), (180.0, 0.0, 15.0)], speed=10.0)
    res = fly(plan, [fa.policy.Geofence()], until=60.0)
    breaches = [e for e in res.events if e["kind"] == "geofence_breach"]
    assert len(breaches) == 1 and breaches[0]["action"] == "hold"
    assert res.kpis["geofence_breaches"] == 1
    assert farthest(res) < WORLD / 2
    assert farthest(res) > WORLD / 2 - 30.0         # it flew on until its braking distance


def test_return_home_on_breach_and_a_user_polygon_and_ceiling():
    plan = fa.pilots.Waypoints([(0.0, 0.0, 15.0), (60.0, 0.0, 15.0)], speed=8.0)
    fence = fa.policy.Geofence([(-30.0, -30.0), (30.0, -30.0), (30.0, 30.0), (-30.0, 30.0)],
                               action="return_home")
    res = fly(plan, [fence], until=80.0)
    assert res.kpis["geofence_breaches"] == 1 and res.end_reason == "landed"
    assert farthest(res) < 30.0
    high = fa.pilots.Waypoints([(0.0, 0.0, 15.0), (0.0, 0.0, 40.0)], speed=4.0)
    res = fly(high, [fa.policy.Geofence(ceiling_m=25.0, action="land")], until=60.0)
    (b,) = [e for e in res.events if e["kind"] == "geofence_breach"]
    assert b["why"] == "above the ceiling" and res.telemetry["z"].max() < 28.0


def test_a_goto_outside_a_user_geofence_is_refused():
    fence = fa.policy.Geofence([(-30.0, -30.0), (30.0, -30.0), (30.0, 30.0), (-30.0, 30.0)])
    pol = Scripted([(15.0, lambda d: d.goto(50.0, 0.0))])
    res = fly(fa.pilots.Hover(altitude=15.0), [pol, fence], until=25.0)
    (r,) = [e for e in res.events if e["kind"] == "policy_refused"]
    assert "outside geofence 'geofence'" in r["reason"]


def test_bad_geofences_are_config_errors():
    with pytest.raises(ConfigError, match="action = 'explode'.*allowed"):
        fa.policy.Geofence(action="explode")
    with pytest.raises(ConfigError, match="polygon = .*at least 3"):
        fa.policy.Geofence([(0.0, 0.0), (1.0, 1.0)])
    with pytest.raises(ConfigError, match="ceiling_m"):
        fa.policy.Geofence(ceiling_m=-5.0)
    assert inside([(0, 0), (10, 0), (10, 10), (0, 10)], 5, 5)
    assert not inside([(0, 0), (10, 0), (10, 10), (0, 10)], 15, 5)


def stuck(frame):
    """A false positive: one 'person' box stuck at the same pixels in every frame,
    below the image centre (a point on the ground ahead of the drone)."""
    h, w = frame.shape[:2]
    return np.array([[0.5 * w - 4, 0.8 * h - 8, 0.5 * w + 4, 0.8 * h + 8, 0.9, 0.0]],
                    dtype=np.float32)


@pytest.mark.slow
def test_a_box_stuck_at_one_pixel_no_longer_flies_the_drone_out_of_the_world():
    eye = fa.Task(fa.ml.PythonModel(stuck, macs=1_000_000), period_s=0.2, classes=("person",),
                  name="eye")
    follow = fa.policy.Follow("eye", target="person", lost_after_s=3.0)
    res = fly(fa.pilots.Hover(altitude=20.0), [follow, fa.policy.Geofence()], until=50.0,
              tasks=[eye])
    modes = [e["mode"] for e in res.events if e["kind"] == "policy_mode"]
    assert "follow" in modes                          # the false positive was chased...
    assert farthest(res) < WORLD / 2                  # ...but the drone stayed in the world
    # the chase was stopped: a track faster than a person, or the fence
    assert res.kpis["track_rejected_implausible"] + res.kpis["geofence_breaches"] >= 1
