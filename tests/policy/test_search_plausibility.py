"""The searches judge a target before acting on it (policy/plausible.py). A box
stuck at one pixel maps to a ground point that moves with the drone: SharedSearch and
SearchThenOrbit reject it (an event, a KPI) instead of chasing it, and still find the
real people around it."""

import math

import numpy as np
import pytest

import pytest_flockai as fa
from pytest_flockai.policy import plausible
from pytest_flockai.policy.follow import MAX_SPEED_MPS
from pytest_flockai.world.truth import CLASSES

AREA = ((-60.0, -60.0), (60.0, 60.0))
WALKERS = fa.actors.walkers(5, ((-55.0, -55.0), (55.0, 55.0)), seed=4)


class StuckOracle(fa.ml.Oracle):
    """The truth boxes plus a false positive: one 'person' box stuck at the same pixels in
    every frame, below the image centre (as in tests/policy/test_geofence.py)."""

    def __call__(self, frame):
        h, w = frame.shape[:2]
        stuck = [0.5 * w - 4, 0.8 * h - 8, 0.5 * w + 4, 0.8 * h + 8, 0.9, CLASSES.index("person")]
        return np.vstack([super().__call__(frame), np.array([stuck])])

    def to_dict(self):
        return {**super().to_dict(), "type": "StuckOracle"}


def fleet(stuck: bool):
    station = fa.policy.GroundStation((0.0, 0.0, 0.0))
    drones = []
    for i, (pilot, pad) in enumerate(fa.fleet.survey(AREA, 3, altitude=20.0, spacing=15.0,
                                                     speed=6.0)):
        model = (StuckOracle if stuck else fa.ml.Oracle)(classes=["person"])
        eye = fa.Task(model, period_s=0.5, evaluate="detection", name="eye")
        drones.append(fa.FleetDrone(
            f"d{i + 1}", fa.drone("dji-mavic-2-pro"), pilot, pad=pad, tasks=[eye], seed=i,
            policies=[fa.policy.SharedSearch("eye", station, orbit_s=10.0)]))
    return fa.Fleet(drones, world=fa.World.scene(size=(140.0, 140.0)), actors=WALKERS)


@pytest.mark.slow
def test_a_box_stuck_at_one_pixel_sends_no_drone_of_a_shared_search_after_a_phantom():
    # before the gate: the stuck box was reported at every confirmation,
    # the drones were sent after it and no walker was found
    clean, res = fleet(False).run(), fleet(True).run()
    c, k = clean.kpis, res.kpis
    assert k["fleet.targets_found"] == c["fleet.targets_found"] == 5
    assert k["fleet.makespan_s"] == pytest.approx(c["fleet.makespan_s"], rel=0.05)
    assert k["fleet.assignments"] == c["fleet.assignments"]
    # every orbit (an assignment flown) is centred on a walker, none on the phantom
    orbits = [e for e in res.events if e["kind"] == "policy" and e["action"] == "orbit"]
    assert len(orbits) == k["fleet.assignments"]
    for o in orbits:
        assert min(math.dist((o["x"], o["y"]), p.at(o["t"])[:2]) for p in WALKERS) < 10.0
    rejected = [e for e in res.events if e["kind"] == "target_rejected"]
    assert {e["drone"] for e in rejected} == {"d1", "d2", "d3"}
    assert all(e["reason"] == "with_drone" and "box fixed in the image" in e["why"]
               for e in rejected)
    for d in ("d1", "d2", "d3"):
        assert k[f"{d}.targets_rejected_implausible"] >= 1
        assert c[f"{d}.targets_rejected_implausible"] == 0      # no walker was rejected
    assert k["fleet.min_separation_m"] >= 0.9 * c["fleet.min_separation_m"]


@pytest.mark.slow
def test_search_then_orbit_rejects_the_stuck_box_and_still_finds_the_walker():
    walker = fa.actors.Person([(30.0, 25.0), (40.0, 25.0)], speed=1.4, loop=True, name="p1")
    task = fa.Task(StuckOracle(classes=["person"]), period_s=0.5, evaluate="detection",
                   name="eye")
    res = fa.Mission(fa.drone("dji-mavic-2-pro"),
                     fa.pilots.ZigZag(area=((-50, -45), (50, 45)), altitude=20.0, spacing=25.0,
                                      speed=6.0),
                     world=fa.World.scene(size=(120.0, 120.0)), tasks=[task], actors=[walker],
                     policies=[fa.policy.SearchThenOrbit("eye", find=1, orbit_s=10.0)],
                     until="landed").run()
    k = res.kpis
    assert k["targets_found"] == 1 and k["targets_rejected_implausible"] >= 1
    (orbit,) = [e for e in res.events if e["kind"] == "policy" and e["action"] == "orbit"]
    assert math.dist((orbit["x"], orbit["y"]), walker.at(orbit["t"])[:2]) < 2.0
    first = next(e for e in res.events if e["kind"] == "target_rejected")
    assert first["t"] < orbit["t"] and first["relative_m"] < 1.0


def hits(target, drone, n=4, dt=0.5):
    """Raw hits of a track: the target and the drone each at constant velocity (m/s)."""
    return [(i * dt, (5.0 + target[0] * i * dt, 2.0 + target[1] * i * dt),
             (drone[0] * i * dt, drone[1] * i * dt, 0.0)) for i in range(n)]


def test_the_rule_rejects_what_moves_with_the_drone_and_keeps_walkers():
    person = MAX_SPEED_MPS["person"]
    assert plausible.judge(hits((6.0, 0.0), (6.0, 0.0)), person)[0] == "with_drone"
    assert plausible.judge(hits((0.0, 0.0), (6.0, 0.0)), person) is None       # standing
    # a walker at the fastest walking pace, any direction, under a drone at 6 m/s
    for a in np.linspace(0.0, 2 * math.pi, 12, endpoint=False):
        v = plausible.WALK_MAX_MPS
        assert plausible.judge(hits((v * math.cos(a), v * math.sin(a)), (6.0, 0.0)), person) \
            is None
    # faster than a person (the 100 m record) between two hits
    assert plausible.judge(hits((12.0, 0.0), (0.0, 6.0)), person)[0] == "faster"
    # the limit: a target keeping pace with the drone is rejected, even a real runner
    assert plausible.judge(hits((5.0, 0.0), (6.0, 0.0)), person)[0] == "with_drone"


def test_a_still_or_slow_drone_cannot_judge_and_waits():
    person = MAX_SPEED_MPS["person"]
    # hovering: the stuck box is a still point; acted on after WAIT_S, not before
    assert plausible.judge(hits((0.0, 0.0), (0.0, 0.0), n=3), person) == ("wait", {})
    n = int(plausible.WAIT_S / 0.5) + 1
    assert plausible.judge(hits((0.0, 0.0), (0.0, 0.0), n=n), person) is None
    # a drone at 2 m/s (a walker could keep pace): never judged, never acted on unjudged
    assert plausible.judge(hits((2.0, 0.0), (2.0, 0.0), n=3 * n), person) == ("wait", {})
