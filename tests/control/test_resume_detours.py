"""``resume()`` returns to exactly where the plan was left, however many
detours (orbit, hold, goto) came before, and whether the previous resume had reached
the plan again or was still on its way back. Observable: a ZigZag flown with detours
still passes over every one of its corners (a plan whose clock jumps skips legs)."""

import math

import pytest
from hypothesis import Phase, example, given, settings
from hypothesis import strategies as st

import pytest_flockai as fa

SURVEY = fa.pilots.ZigZag(area=((0.0, 0.0), (60.0, 40.0)), altitude=15.0, spacing=20.0,
                          speed=8.0)
KINDS = ("orbit", "hold", "goto")


class Detours(fa.Policy):
    """Leave the plan ``gap`` s after the last resume (or after take-off), stay away
    ``away`` s, resume; once per entry of ``script`` [(kind, gap, away), ...]."""

    def __init__(self, script):
        super().__init__(name="detours", period_s=0.1)
        self.script = list(script)

    def start(self, run):
        self.i, self.t_next, self.away_until = 0, None, None

    def decide(self, t, drone):
        if drone.stage != "pilot" or self.i >= len(self.script):
            return
        kind, gap, away = self.script[self.i]
        if self.t_next is None:
            self.t_next = t + gap
        if self.away_until is None and t >= self.t_next:
            x, y, _ = drone.position
            {"orbit": lambda: drone.orbit(x + 12.0, y, radius=12.0, speed=4.0),
             "hold": drone.hold,
             "goto": lambda: drone.goto(x - 15.0, y + 10.0, 20.0)}[kind]()
            self.away_until = t + away
        elif self.away_until is not None and t >= self.away_until:
            drone.resume()
            self.i, self.away_until = self.i + 1, None
            if self.i < len(self.script):
                self.t_next = t + self.script[self.i][1]


def fly(script):
    return fa.Mission(fa.drone("dji-mavic-2-pro"), SURVEY, world=fa.World.scene(size=(300.0, 300.0)),
                      policies=[Detours(script)], until=400.0, seed=0).run()


def corners_missed(res, tol=1.5):
    xy = res.telemetry[["x", "y"]].to_numpy()
    return [p[:2] for p in SURVEY.points
            if min(math.dist(q, p[:2]) for q in xy) > tol]


detour = st.tuples(st.sampled_from(KINDS), st.floats(1.0, 10.0), st.floats(2.0, 10.0))


# no shrinking: each example is a flight of seconds, and a failing one is shown as found
@settings(max_examples=10, deadline=None, derandomize=True,
          phases=(Phase.explicit, Phase.reuse, Phase.generate))
@pytest.mark.slow
@given(st.lists(detour, min_size=1, max_size=4))
@example([("orbit", 4.0, 8.0), ("orbit", 4.0, 8.0)])        # the case: two orbits
@example([("hold", 3.0, 6.0), ("goto", 1.0, 6.0), ("orbit", 1.0, 6.0)])   # left on the way back
def test_resume_after_any_detours_returns_where_the_plan_was_left(script):
    res = fly(script)
    actions = [e["action"] for e in res.events if e["kind"] == "policy"]
    assert actions.count("resume") == len(script), actions
    assert corners_missed(res) == []
    assert res.end_reason == "landed"
