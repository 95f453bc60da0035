"""The Cockpit's attitude view and the heading of its goto (policy/attitude.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import pytest_flockai as fa
from pytest_flockai.control.pilots import Hover, Waypoints
from pytest_flockai.errors import ConfigError

DRONE = "dji-mavic-2-pro"


class Watch(fa.Policy):
    """Records the Cockpit's attitude in ``Watch.log`` (the flight runs a bound copy of
    the policy); at ``at`` s (pilot stage) flies ``goto`` (``Watch.sent``: accepted)."""

    log: list = []
    sent = False

    def __init__(self, goto=None, at=2.0):
        super().__init__("watch", period_s=0.1)
        self.goto, self.at = goto, at

    def start(self, run):
        Watch.log, Watch.sent = [], False

    def decide(self, t, drone):
        a = drone.attitude
        Watch.log.append((t, a.roll, a.pitch, a.yaw, a.heading_deg, drone.yaw))
        if self.goto is not None and not Watch.sent and t >= self.at and drone.stage == "pilot":
            Watch.sent = drone.goto(*self.goto[0], **self.goto[1])


def fly(pilot, policy, until):
    m = fa.Mission(fa.drone(DRONE), pilot, policies=[policy], until=until)
    run = m.run()
    return run, np.array(Watch.log)


def test_attitude_is_the_drone_s_roll_pitch_and_heading_while_it_flies_east():
    w = Watch()
    res, seen = fly(Waypoints([(30.0, 0.0, 10.0)], 6.0), w, 20.0)
    t, roll, pitch, yaw, hdg, cockpit_yaw = seen.T
    np.testing.assert_allclose(yaw, cockpit_yaw, atol=1e-9)       # the same quaternion
    np.testing.assert_allclose(hdg, (90.0 - np.degrees(yaw)) % 360.0, atol=1e-9)
    assert abs(np.median(hdg[t > 5]) - 90.0) < 5.0               # facing east: compass 90
    tel = res.telemetry
    # the drone tilts its nose down to speed up toward +x: pitch > 0 (module docstring)
    moving = (t > 4) & (t < 8)
    assert np.max(pitch[moving]) > math.radians(3)
    # and its roll and pitch are the simulator's own, sampled at the same times
    for name, vals in (("roll", roll), ("pitch", pitch)):
        ref = np.interp(t, tel["t"] if "t" in tel else tel.index.to_numpy(), tel[name])
        assert np.max(np.abs(vals - ref)) < math.radians(3), name


def test_goto_with_a_yaw_turns_the_drone_to_it_and_without_keeps_east():
    north = Watch(goto=((5.0, 5.0, 8.0), {"yaw": math.pi / 2}))
    _, seen = fly(Hover(8.0), north, 15.0)
    assert Watch.sent
    assert abs(seen[-1, 4] - 0.0) < 5.0 or abs(seen[-1, 4] - 360.0) < 5.0   # compass north
    plain = Watch(goto=((5.0, 5.0, 8.0), {}))
    _, seen = fly(Hover(8.0), plain, 15.0)
    assert abs(seen[-1, 4] - 90.0) < 5.0                          # east, as before


@pytest.mark.parametrize("bad", ["north", math.nan, math.inf, True])
def test_goto_yaw_that_is_not_an_angle_is_named(bad):
    with pytest.raises(ConfigError, match=r"goto\(yaw = .*finite angle in radians"):
        fly(Hover(8.0), Watch(goto=((5.0, 5.0, 8.0), {"yaw": bad})), 12.0)
