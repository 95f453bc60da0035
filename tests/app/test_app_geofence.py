"""The geofence an app sets, as PX4 keeps it: uploaded, downloaded and cleared with the
mission protocol (MAV_MISSION_TYPE_FENCE), checked in flight, and acted on as GF_ACTION
says. Real programs (tests/app/apps/) and the fence's geometry on its own."""

from __future__ import annotations

import os
import sys

import numpy as np
import pytest

import pytest_flockai as fa
from pytest_flockai.app import frames
from pytest_flockai.app.boundary import CIRCLE_OUT, POLY_IN, POLY_OUT, Boundary, check

pytest.importorskip("pymavlink")
APPS = os.path.join(os.path.dirname(__file__), "apps")
DRONE = "dji-mavic-2-pro"
GEO = frames.Geo((0.0, 0.0, 0.0))


def run(name, *args, speed=4.0):
    return fa.app.run([sys.executable, os.path.join(APPS, name), *args], fa.drone(DRONE),
                      speed=speed, timeout_s=120)


def item(seq, cmd, p1, x, y):
    lat, lon, _, _ = GEO.to_global(x, y, 0.0)
    return {"seq": seq, "command": cmd, "p": [p1, 0, 0, 0], "x": lat, "y": lon, "z": 0.0}


def square(cmd, half, seq0=0, cx=0.0, cy=0.0):
    return [item(seq0 + i, cmd, 4.0, cx + a * half, cy + b * half)
            for i, (a, b) in enumerate(((-1, -1), (1, -1), (1, 1), (-1, 1)))]


def test_inside_is_in_an_inclusion_zone_and_in_no_exclusion_zone():
    fence = square(POLY_IN, 20.0) + square(POLY_OUT, 3.0, seq0=4, cx=10.0) + [
        item(8, CIRCLE_OUT, 4.0, -10.0, 0.0)]
    assert check(fence) is None
    b = Boundary(fence, GEO)
    assert b.breach(0.0, 0.0, 5.0) is None
    assert b.breach(0.0, 25.0, 5.0) == "outside the geofence's inclusion zones"
    assert b.breach(10.0, 1.0, 5.0) == "inside an exclusion zone of the geofence"
    assert b.breach(-10.0, 3.0, 5.0) == "inside an exclusion zone of the geofence"
    assert b.breach(-10.0, 5.0, 5.0) is None
    # the distances from home apply with or without an uploaded fence
    assert "GF_MAX_VER_DIST" in Boundary([], GEO).breach(0.0, 0.0, 31.0, 0.0, 30.0)
    assert "GF_MAX_HOR_DIST" in Boundary([], GEO).breach(30.0, 40.0, 5.0, 49.0, 0.0)
    assert Boundary([], GEO).breach(30.0, 40.0, 5.0, 51.0, 0.0) is None


def test_a_fence_that_is_not_one_is_named_by_its_item():
    assert check(square(POLY_IN, 5.0)[:3]) == (0, "a polygon of 4 vertices has 3 items of its "
                                                   "kind in a row; allowed: its vertices one "
                                                   "after the other")
    broken = square(POLY_IN, 5.0)[:2] + [item(2, CIRCLE_OUT, 1.0, 0.0, 0.0)] + \
        square(POLY_IN, 5.0, seq0=3)[2:]
    assert check(broken)[1].startswith("a polygon of 4 vertices has 2 items of its kind")
    two = [dict(v, p=[2.0, 0, 0, 0]) for v in square(POLY_IN, 5.0)[:2]]
    assert check(two)[1].startswith("a polygon's vertex count (param1) is 2.0")
    assert "radius (param1) is 0.0" in check([item(0, CIRCLE_OUT, 0.0, 0.0, 0.0)])[1]


def test_a_pymavlink_program_uploads_downloads_and_clears_a_fence():
    r = run("pymavlink_fence.py")
    assert r.exit_code == 0, r.output
    for line in ("upload MAV_MISSION_ACCEPTED", "download 5 items as uploaded",
                 "clear MAV_MISSION_ACCEPTED", "after clear 0 items",
                 "two vertices MAV_MISSION_INVALID", "rally MAV_MISSION_UNSUPPORTED",
                 "GF_ACTION 3 MAV_PARAM_TYPE_INT32"):
        assert line in r.output, r.output
    refused = [e for e in r.result.events if e["kind"] == "app_mission_refused"]
    assert [(e["seq"], e["item"]) for e in refused] == [(0, "NAV_FENCE_POLYGON_VERTEX_INCLUSION")]
    rally = [e for e in r.result.events if e["kind"] == "app_not_emulated"]
    assert [e["reason"] for e in rally] == ["rally points (MAV_MISSION_TYPE_RALLY) are not flown"]
    assert r.result.kpis["app.commands_unsupported"] == 2.0


def north_m(res):
    return float(np.max(res.telemetry["y"] - res.telemetry["y"].iloc[0]))


def test_mavsdk_geofence_holds_the_drone_at_its_edge():
    r = run("mavsdk_geofence.py")           # PX4's default GF_ACTION, 2: hold
    assert r.exit_code == 0, r.output
    assert "GF_ACTION 2" in r.output and "mode HOLD" in r.output and "landed" in r.output
    res = r.result
    (breach,) = [e for e in res.events if e["kind"] == "app_geofence_breach"]
    assert breach["action"] == "hold" and breach["acted"] and "inclusion" in breach["reason"]
    assert 19.5 < breach["y"] < 21.0                # caught within a step of the 20 m edge
    assert 20.0 < north_m(res) < 24.0               # it stopped, braking, just past it
    assert res.kpis["app.geofence_breaches"] == 1.0 and res.end_reason == "landed"


def test_mavsdk_geofence_with_return_brings_the_drone_home():
    r = run("mavsdk_geofence.py", "3")
    assert r.exit_code == 0, r.output
    assert "GF_ACTION 3" in r.output and "mode RETURN_TO_LAUNCH" in r.output, r.output
    res = r.result
    (breach,) = [e for e in res.events if e["kind"] == "app_geofence_breach"]
    assert breach["action"] == "return"
    end = res.telemetry.iloc[-1]
    assert res.end_reason == "landed" and np.hypot(end["x"], end["y"]) < 1.5


def test_an_integer_parameter_is_read_byte_wise_or_as_its_number():
    from pytest_flockai.app.mavlink_udp import _as_float, _int_of
    assert _as_float(3) != 3.0 and _int_of(_as_float(3), range(6)) == 3    # PX4, MAVSDK
    assert _int_of(_as_float(0), range(6)) == 0
    assert _int_of(3.0, range(6)) == 3                  # a client that sends the number
    assert _int_of(7.0, range(6)) is None and _int_of(float("nan"), range(6)) is None


def test_mavsdk_goto_outside_the_geofence_leaves_the_drone_where_it_is():
    r = run("mavsdk_geofence.py", "goto")
    assert r.exit_code == 0, r.output
    assert "landed" in r.output
    res = r.result
    (refused,) = [e for e in res.events if e["kind"] == "app_reposition_refused"]
    assert refused["reason"] == "the target is outside the geofence's inclusion zones"
    assert 39.0 < refused["y"] < 41.0
    goto = [e for e in res.events if e["kind"] == "app_command" and e["command"] == "DO_REPOSITION"]
    assert [e["result"] for e in goto] == ["ACCEPTED"]      # PX4's commander acknowledges it
    tel = res.telemetry
    assert np.max(np.hypot(tel["x"] - tel["x"].iloc[0], tel["y"] - tel["y"].iloc[0])) < 1.0
    assert res.kpis["app.geofence_breaches"] == 0.0 and res.end_reason == "landed"
