"""How the simulated autopilot paces the simulation against the wall clock: what the
app sees (telemetry, the effect and acknowledgement of its commands) is on the paced
clock, the steps in between run in bursts, so the simulation wakes at the telemetry's
rate and not at every 40 ms step. A real pymavlink program flies (tests/apps)."""

from __future__ import annotations

import os
import sys
import time

import pytest

import pytest_flockai as fa
from pytest_flockai.app import autopilot as ap_mod
from pytest_flockai.app import mavlink_udp as link_mod

pytest.importorskip("pymavlink")
HOP = [sys.executable, os.path.join(os.path.dirname(__file__), "apps", "pymavlink_hop.py")]


@pytest.mark.slow
def test_the_simulation_wakes_at_the_telemetry_rate_and_acts_on_commands_on_time(monkeypatch):
    waits, arrived, acted = [], {}, []
    pace, handle, receive = ap_mod.Autopilot._pace, ap_mod.Autopilot.handle, link_mod.Link._handle

    def timed_pace(self, t):
        w = time.monotonic()
        now = pace(self, t)
        if now - w > 0.003:                 # it slept or waited for a message
            waits.append(t)
        return now

    def stamped_receive(self, msg):
        if self.sim_running and msg.get_type().startswith("COMMAND"):
            arrived[msg.command] = time.monotonic()
        return receive(self, msg)

    def timed_handle(self, t, msg):
        if msg.get_type().startswith("COMMAND") and msg.command in arrived:
            at = arrived[msg.command]
            acted.append((msg.command, time.monotonic() - at, self.wall - at))
        return handle(self, t, msg)

    monkeypatch.setattr(ap_mod.Autopilot, "_pace", timed_pace)
    monkeypatch.setattr(ap_mod.Autopilot, "handle", timed_handle)
    monkeypatch.setattr(link_mod.Link, "_handle", stamped_receive)
    speed = 4.0
    r = fa.app.run(HOP, fa.drone("dji-mavic-2-pro"), speed=speed, timeout_s=90)
    assert r.exit_code == 0, r.output
    flown = r.result.scenario["sim_time_s"]
    # 10 Hz telemetry: about 10 waits a simulated second (one per 40 ms step would be 25)
    assert 5.0 < len(waits) / flown < 14.0, (len(waits), flown)
    # each command acts at a step paced after its arrival (never at an earlier one),
    # computed then: within one step of wall time, plus the machine's jitter
    assert len(acted) >= 4, r.output        # ARM, TAKEOFF, DO_REPOSITION, LAND...
    for cmd, delay, paced_after in acted:
        assert paced_after >= 0.0, (cmd, paced_after)
        assert 0.0 <= delay < ap_mod.PERIOD_S / speed + 0.05, (cmd, delay)
