"""Real MAVLink programs fly the simulated drone (pytest_flockai.app): MAVSDK-Python and
pymavlink programs written for these tests (tests/app/apps/), run as separate processes."""

from __future__ import annotations

import math
import os
import socket
import sys
import threading
import time

import numpy as np
import pytest

import pytest_flockai as fa
from pytest_flockai.errors import ConfigError

pytest.importorskip("pymavlink")
APPS = os.path.join(os.path.dirname(__file__), "apps")
DRONE = "dji-mavic-2-pro"


def app(name: str) -> list:
    return [sys.executable, os.path.join(APPS, name)]


def mavsdk_available() -> bool:
    from importlib.metadata import PackageNotFoundError, version
    try:
        return int(version("mavsdk").split(".")[0]) < 4
    except PackageNotFoundError:
        return False


needs_mavsdk = pytest.mark.skipif(not mavsdk_available(),
                                  reason="needs mavsdk<4 (the gRPC API with mavsdk_server)")


def events(res, kind):
    return [e for e in res.events if e["kind"] == kind]


def test_pymavlink_program_flies_its_commands_and_lands():
    r = fa.app.run(app("pymavlink_hop.py"), fa.drone(DRONE), speed=4.0, timeout_s=60)
    assert r.exit_code == 0, r.output
    res = r.result
    assert res.end_reason == "landed"
    k = res.kpis
    # NAV_TAKEOFF before ARM is denied (as PX4 does), DO_SET_HOME is not emulated
    assert (k["app.commands_denied"], k["app.commands_unsupported"]) == (1.0, 1.0)
    assert k["app.speed"] == 4.0 and k["app.lag_max_s"] >= 0.0
    assert res.scenario["app"]["speed"] == 4.0
    cmds = [(e["command"], e["result"]) for e in events(res, "app_command")]
    assert cmds[:3] == [("NAV_TAKEOFF", "DENIED"), ("COMPONENT_ARM_DISARM", "ACCEPTED"),
                        ("NAV_TAKEOFF", "ACCEPTED")]
    tel = res.telemetry
    assert tel["z"].max() == pytest.approx(4.0 + tel["z"].iloc[0], abs=0.5)   # MIS_TAKEOFF_ALT
    assert tel["y"].max() == pytest.approx(10.0, abs=1.0)      # 10 m north (GPS-grade estimate)
    assert abs(tel["y"].iloc[-1] - 10.0) < 1.0 and abs(tel["x"]).max() < 1.0


@pytest.mark.slow
@needs_mavsdk
@pytest.mark.flockai_app(cmd=app("mavsdk_takeoff_land.py"), timeout_s=90)
@pytest.mark.kpi(flight_time_s="<= 20 s", **{"app.commands_denied": "== 0"})
def test_mavsdk_take_off_and_land_within_a_flight_time_budget(flight):
    assert flight.end_reason == "landed"
    assert flight.kpis["app.exit_code"] == 0.0
    tel = flight.telemetry
    assert tel["z"].max() - tel["z"].iloc[0] == pytest.approx(5.0, abs=0.4)   # set by the app


@pytest.mark.slow
@needs_mavsdk
def test_mavsdk_offboard_position_setpoints_fly_a_square_with_headings():
    r = fa.app.run(app("mavsdk_offboard.py"), fa.drone(DRONE), speed=2.0, timeout_s=120)
    assert r.exit_code == 0, r.output
    tel = r.result.telemetry
    xy = tel[["x", "y"]].to_numpy()
    for east, north in ((0, 10), (10, 10), (10, 0)):             # the square's corners
        assert np.min(np.hypot(xy[:, 0] - east, xy[:, 1] - north)) < 0.6
    yaw = tel["yaw"].to_numpy()
    for heading in (0, 90, 180, 270):                            # north, east, south, west
        want = math.atan2(math.cos(math.radians(heading)), math.sin(math.radians(heading)))
        assert np.min(np.abs(np.angle(np.exp(1j * (yaw - want))))) < 0.1, heading


@pytest.mark.slow
@needs_mavsdk
def test_mavsdk_velocity_body_setpoints_turn_at_the_yaw_rate_asked():
    """MAVSDK's set_velocity_body with a yaw speed (30 deg/s clockwise, 2 m/s forward):
    the drone turns at that rate (PX4 flies a yaw rate where no yaw is given), its
    heading telemetry follows, and it flies a curve, not a line."""
    r = fa.app.run(app("mavsdk_velocity_body.py"), fa.drone(DRONE), speed=2.0, timeout_s=120)
    assert r.exit_code == 0, r.output
    tel = r.result.telemetry
    yaw = np.unwrap(tel["yaw"].to_numpy())
    rate = np.degrees(np.diff(yaw) / np.diff(tel.index.to_numpy()))
    turning = rate[np.abs(rate) > 5.0]
    assert len(turning) > 20 and np.median(turning) == pytest.approx(-30.0, abs=2.0)
    before, after = (float(line.split()[-1]) for line in r.output.splitlines()
                     if line.startswith("heading "))
    turned = (after - before) % 360.0                  # clockwise, as MAVLink's headings
    assert turned == pytest.approx(np.degrees(yaw[0] - yaw[-1]) % 360.0, abs=3.0)
    assert turned > 90.0
    xy = tel[["x", "y"]].to_numpy()
    assert np.ptp(xy[:, 0]) > 2.0 and np.ptp(xy[:, 1]) > 2.0        # a curve


@pytest.mark.slow
@needs_mavsdk
def test_mavsdk_mission_gives_the_same_kpis_at_speed_1_and_20():
    runs = {}
    for speed in (20.0, 1.0):
        r = fa.app.run(app("mavsdk_mission.py"), fa.drone(DRONE), speed=speed, timeout_s=120)
        assert r.exit_code == 0, r.output
        runs[speed] = r
    a, b = (dict(runs[s].result.kpis) for s in (1.0, 20.0))
    for k in ("app.speed", "app.lag_max_s", "app.lag_mean_s"):
        a.pop(k), b.pop(k)
    assert a == b
    assert runs[20.0].wall_s < runs[1.0].wall_s / 3
    res = runs[1.0].result
    assert res.end_reason == "landed" and [e["stage"] for e in events(res, "stage")][-3:] == \
        ["return", "landing", "landed"]
    xy = res.telemetry[["x", "y"]].to_numpy()
    for east, north in ((0, 20), (15, 20), (15, 0)):
        assert np.min(np.hypot(xy[:, 0] - east, xy[:, 1] - north)) < 1.0


@pytest.mark.slow
@needs_mavsdk
def test_mavsdk_orbit_circles_the_point_and_returns():
    r = fa.app.run(app("mavsdk_orbit.py"), fa.drone(DRONE), speed=2.0, timeout_s=120)
    assert r.exit_code == 0, r.output
    res = r.result
    assert res.end_reason == "landed"
    tel = res.telemetry
    d = np.hypot(tel["x"] - 15.0, tel["y"])
    on_circle = tel[(d > 7.0) & (d < 9.0)]
    assert len(on_circle) > 20
    assert ("DO_ORBIT", "ACCEPTED") in [(e["command"], e["result"]) for e in events(res, "app_command")]


@pytest.mark.slow
def test_two_apps_at_once_each_fly_only_their_own_drone():
    out: dict = {}

    def fly(north):
        out[north] = fa.app.run(app("pymavlink_hop.py"), fa.drone(DRONE), speed=4.0,
                                timeout_s=90, env={"HOP_NORTH_M": str(north)})

    threads = [threading.Thread(target=fly, args=(n,)) for n in (12.0, -8.0)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert out[12.0].port != out[-8.0].port
    for north, r in out.items():
        assert r.exit_code == 0, r.output
        y = r.result.telemetry["y"]
        assert y.iloc[-1] == pytest.approx(north, abs=1.0)
        assert (y.max() if north > 0 else -y.min()) < abs(north) + 1.0


@pytest.mark.slow
@pytest.mark.parametrize("north", [6.0, -6.0])
def test_app_tests_in_parallel_workers_never_cross(north):
    """Run with ``-n 2``: both fly at once, each must end where its own app sent it."""
    r = fa.app.run(app("pymavlink_hop.py"), fa.drone(DRONE), speed=4.0, timeout_s=90,
                   env={"HOP_NORTH_M": str(north)})
    assert r.exit_code == 0, r.output
    assert r.result.telemetry["y"].iloc[-1] == pytest.approx(north, abs=1.0)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    with open(f"/proc/{pid}/stat") as f:                  # a zombie waiting for init
        return f.read().split(")")[-1].split()[0] != "Z"


@pytest.mark.slow
def test_a_hanging_app_fails_in_time_naming_what_it_waited_for_and_leaves_nothing():
    t0 = time.monotonic()
    with pytest.raises(fa.app.AppError) as info:
        fa.app.run(app("pymavlink_hang.py"), fa.drone(DRONE), timeout_s=6)
    assert time.monotonic() - t0 < 6 + 8
    msg = str(info.value)
    assert "timeout_s = 6 s" in msg and "ESTIMATOR_STATUS" in msg and "on the ground" in msg
    err = info.value
    child = int(err.output.split("child")[1].split()[0])
    assert not _alive(child)                                   # the app's whole group is gone
    port = err.result.scenario["app"]["port"]
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("0.0.0.0", port))                              # its port is free again
    assert err.result.end_reason == "app_timeout"


@pytest.mark.slow
def test_an_app_that_raised_but_stayed_alive_is_named_by_its_exception():
    """A traceback and a process kept alive by a thread: the hang's message leads with
    the exception, not only with the last MAVLink message."""
    with pytest.raises(fa.app.AppError) as info:
        fa.app.run(app("pymavlink_hang.py"), fa.drone(DRONE), timeout_s=5,
                   env={"HANG_RAISE": "1"})
    msg = str(info.value)
    assert "the app raised RuntimeError: lost the vehicle (its output ends in a Python " \
           "traceback) but did not exit" in msg
    assert "ESTIMATOR_STATUS" in msg                 # what it waited for is still said
    assert fa.app.launch.raised_in("ok\n") is None


def test_an_input_px4_flies_and_the_front_end_does_not_is_named_once():
    """Attitude setpoints (SET_ATTITUDE_TARGET, three of them): one app_not_emulated event,
    one more unsupported; the rest of the flight goes on."""
    r = fa.app.run(app("pymavlink_hop.py"), fa.drone(DRONE), speed=4.0, timeout_s=60,
                   env={"HOP_ATTITUDE": "1"})
    assert r.exit_code == 0, r.output
    (ev,) = events(r.result, "app_not_emulated")
    assert ev["message"] == "SET_ATTITUDE_TARGET" and "attitude setpoints" in ev["reason"]
    assert r.result.kpis["app.commands_unsupported"] == 2.0       # and DO_SET_HOME
    assert r.result.end_reason == "landed"


def test_an_app_dying_in_the_air_leaves_the_drone_to_return_and_land():
    r = fa.app.run(app("pymavlink_hop.py"), fa.drone(DRONE), speed=4.0, timeout_s=60,
                   env={"HOP_CRASH": "1"})
    assert r.exit_code == 3 and r.result.kpis["app.exit_code"] == 3.0
    assert "crashing in the air" in r.output
    res = r.result
    (ev,) = events(res, "app_exited")
    assert ev["exit_code"] == 3
    assert res.end_reason == "landed"                          # PX4's link-loss failsafe
    tel = res.telemetry
    assert np.hypot(tel["x"].iloc[-1], tel["y"].iloc[-1]) < 1.0


def test_a_mission_item_the_drone_cannot_fly_is_refused_by_name():
    r = fa.app.run(app("pymavlink_bad_mission.py"), fa.drone(DRONE), timeout_s=30)
    assert r.exit_code == 0, r.output
    assert "mission ack MAV_MISSION_UNSUPPORTED" in r.output
    (ev,) = events(r.result, "app_mission_refused")
    assert ev["item"] == "NAV_LOITER_TURNS" and ev["seq"] == 1
    assert r.result.kpis["app.commands_unsupported"] == 1.0
    assert r.result.end_reason == "app_exited"                 # it never took off


def test_bad_input_is_named(tmp_path):
    drone = fa.drone(DRONE)
    script = tmp_path / "app.py"
    script.write_text("print('hi')\n")
    with pytest.raises(ConfigError, match=r"cmd\[0\] = .*app.py' is not executable"):
        fa.app.run([str(script)], drone)
    with pytest.raises(ConfigError, match=r"cmd\[0\] = 'no-such-app-xyz' does not exist"):
        fa.app.run(["no-such-app-xyz"], drone)
    with pytest.raises(ConfigError, match="cmd = 'python app.py' is not allowed"):
        fa.app.run("python app.py", drone)
    for bad in (0, -1.0, float("nan")):
        with pytest.raises(ConfigError, match="speed"):
            fa.app.run([sys.executable, str(script)], drone, speed=bad)
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
        with pytest.raises(ConfigError, match=f"port = {port} is in use"):
            fa.app.run([sys.executable, str(script)], drone, port=port)


def test_the_default_flight_still_takes_off_at_once():
    res = fa.Mission(fa.drone(DRONE), fa.pilots.Hover(altitude=5.0, duration=1.0)).run()
    assert not [e for e in res.events if e["kind"] == "preflight"]
    assert res.events[0] == {"t": 0.0, "kind": "stage", "stage": "takeoff"}
    assert res.end_reason == "landed"


def test_a_flight_can_wait_on_its_pad_until_a_take_off():
    class Later(fa.Policy):
        def start(self, run):
            self.stages = run.stages
            run.stages.wait_on_ground(0.0)

        def decide(self, t, drone):
            if t >= 2.0 and self.stages.grounded:
                self.stages.take_off(t, self.stages.st.home[2] + 3.0)

    res = fa.Mission(fa.drone(DRONE), fa.pilots.Hover(altitude=10.0, duration=1.0),
                     policies=[Later(period_s=0.1)]).run()
    stages = [(e["t"], e["stage"]) for e in events(res, "stage")]
    assert events(res, "preflight")[0]["t"] == 0.0 and stages[0] == (2.0, "takeoff")
    assert res.end_reason == "landed"
    tel = res.telemetry
    before = tel[tel.index < 1.95]
    assert len(before) and (before["thrust_0"] == 0.0).all()     # motors off on the pad
    assert (before["z"] - tel["z"].iloc[0]).abs().max() < 0.01
    assert tel["z"].max() - tel["z"].iloc[0] == pytest.approx(3.0, abs=0.3)   # set at run time


def _turn_and_faces(tel, cx, cy, r):
    """From the telemetry on the circle about (cx, cy), moving: (the sense of the turn,
    +1 counter-clockwise seen from above, -1 clockwise; the headings; the headings
    toward the centre; the headings along the velocity)."""
    x, y = tel["x"].to_numpy(), tel["y"].to_numpy()
    vx, vy = tel["vx"].to_numpy(), tel["vy"].to_numpy()
    on = (np.abs(np.hypot(x - cx, y - cy) - r) < 1.0) & (np.hypot(vx, vy) > 1.0)
    assert on.sum() > 20                    # 2 s or more on the circle
    spin = np.median((x[on] - cx) * vy[on] - (y[on] - cy) * vx[on])   # angular momentum
    yaw = tel["yaw"].to_numpy()[on]
    return (math.copysign(1.0, spin), yaw, np.arctan2(cy - y[on], cx - x[on]),
            np.arctan2(vy[on], vx[on]))


def _off(a, b):
    return np.abs(np.remainder(a - b + np.pi, 2 * np.pi) - np.pi)


@pytest.mark.parametrize("radius, yaw_mode", [(6.0, 0), (-6.0, 3), (6.0, 1)])
def test_orbit_pilot_turns_as_the_radius_sign_says_and_heads_as_asked(radius, yaw_mode):
    from pytest_flockai.app.pilots import AppOrbit
    pilot = AppOrbit((10.0, 0.0), radius, 5.0, 2.0, yaw_mode, yaw0=0.3)
    res = fa.Mission(fa.drone(DRONE), pilot, until=35.0).run()
    turn, yaw, center, along = _turn_and_faces(res.telemetry, 10.0, 0.0, 6.0)
    assert turn == (-1.0 if radius > 0 else 1.0)   # radius > 0: clockwise
    # the yaw loop trails a heading that turns at speed / radius (0.33 rad/s): ~0.2 rad
    heads = {0: center, 3: along, 1: np.full_like(yaw, 0.3)}
    for mode, want in heads.items():
        off = np.median(_off(yaw, want))
        assert off < math.radians(15) if mode == yaw_mode else off > math.radians(30), mode


@pytest.mark.slow
@pytest.mark.parametrize("radius, yaw_mode", [(6.0, 0), (-6.0, 3)])
def test_do_orbit_from_pymavlink_sets_direction_and_yaw_behaviour(radius, yaw_mode):
    r = fa.app.run(app("pymavlink_orbit.py"), fa.drone(DRONE), speed=4.0, timeout_s=90,
                   env={"ORBIT_RADIUS": str(radius), "ORBIT_YAW": str(yaw_mode)})
    assert r.exit_code == 0, r.output
    cmds = [(e["command"], e["result"]) for e in events(r.result, "app_command")]
    assert ("DO_ORBIT", "UNSUPPORTED") in cmds and ("DO_ORBIT", "ACCEPTED") in cmds
    turn, yaw, center, along = _turn_and_faces(r.result.telemetry, 10.0, 0.0, 6.0)
    assert turn == (-1.0 if radius > 0 else 1.0)
    hz = float(r.output.split("attitude_hz ")[1].split()[0])   # in simulated time
    assert 9.5 < hz < 10.5                  # the 10 Hz stream at 10 Hz on the 25 Hz step
    assert np.median(_off(yaw, center if yaw_mode == 0 else along)) < math.radians(15)


def test_queued_telemetry_goes_out_in_order_in_datagrams_an_app_can_read():
    from pymavlink.dialects.v20 import common as M

    from pytest_flockai.app.mavlink_udp import MAX_DATAGRAM, Link

    rx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    rx.bind(("127.0.0.1", 0))
    rx.settimeout(2.0)
    link = Link(rx.getsockname()[1], ap=None)
    try:
        link.queue([M.MAVLink_attitude_message(i, 0.1, 0.2, 0.3, 0.0, 0.0, 0.0)
                    for i in range(60)])
        assert link.pending
        link.send(M.MAVLink_command_ack_message(M.MAV_CMD_NAV_LAND, 0, 0, 0, 1, 1))
        assert not link.pending
        parser, got, sizes = M.MAVLink(None), [], []
        while len(got) < 61:
            data = rx.recv(65535)
            sizes.append(len(data))
            got += parser.parse_buffer(data) or []
    finally:
        link.sock.close()
        rx.close()
    assert max(sizes) <= MAX_DATAGRAM and len(sizes) < 61      # batched, within the MTU
    assert [g.time_boot_ms for g in got[:60]] == list(range(60))
    assert got[60].get_type() == "COMMAND_ACK"                # after what was queued
    # one sequence number per message, as an autopilot sends (an app counts gaps as loss)
    assert [g.get_seq() for g in got] == [i % 256 for i in range(61)]
    assert parser.total_receive_errors == 0
