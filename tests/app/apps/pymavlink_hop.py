"""A pymavlink program (written for the tests): arm, climb to 4 m, fly $HOP_NORTH_M (10) m north with
DO_REPOSITION, land; exits 0 once the autopilot reports it is on the ground
(with $HOP_CRASH set it exits 3 at 4 m instead, as a crashing app; with $HOP_ATTITUDE set
it also sends attitude setpoints at 4 m, which the simulated autopilot does not fly)."""

import math
import os
import sys
import time

from pymavlink import mavutil

url = os.environ.get("FLOCKAI_MAVLINK_URL", "udpin:0.0.0.0:14540").replace("udpin://", "udpin:")
m = mavutil.mavlink_connection(url, source_system=245, source_component=190)
M = mavutil.mavlink
m.wait_heartbeat(timeout=20)
print("heartbeat from system", m.target_system, flush=True)


def command(cmd, *params, expect=M.MAV_RESULT_ACCEPTED):
    p = list(params) + [0.0] * (7 - len(params))
    m.mav.command_long_send(m.target_system, m.target_component, cmd, 0, *p)
    ack = m.recv_match(type="COMMAND_ACK", blocking=True, timeout=10)
    assert ack is not None and ack.command == cmd, f"no ack for {cmd}"
    print("ack", cmd, ack.result, flush=True)
    assert ack.result == expect, (cmd, ack.result)


def wait(cond, what, timeout=120):
    t0 = time.time()
    while time.time() - t0 < timeout:
        msg = m.recv_match(blocking=True, timeout=1)
        if msg is not None and cond(msg):
            return msg
    sys.exit(f"timed out waiting for {what}")


m.mav.param_set_send(m.target_system, 1, b"MIS_TAKEOFF_ALT", 4.0, M.MAV_PARAM_TYPE_REAL32)
pv = wait(lambda x: x.get_type() == "PARAM_VALUE", "PARAM_VALUE")
assert abs(pv.param_value - 4.0) < 1e-6, pv
home = wait(lambda x: x.get_type() == "HOME_POSITION", "HOME_POSITION")
command(M.MAV_CMD_NAV_TAKEOFF, expect=M.MAV_RESULT_DENIED)      # not armed yet
command(M.MAV_CMD_COMPONENT_ARM_DISARM, 1)
command(M.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, math.nan, math.nan, math.nan, math.nan)
wait(lambda x: x.get_type() == "GLOBAL_POSITION_INT" and x.relative_alt > 3800, "4 m")
if os.environ.get("HOP_CRASH"):
    print("crashing in the air", flush=True)
    os._exit(3)
if os.environ.get("HOP_ATTITUDE"):
    for _ in range(3):
        m.mav.set_attitude_target_send(0, m.target_system, 1, 0b00000111, [1.0, 0.0, 0.0, 0.0],
                                       0.0, 0.0, 0.0, 0.5)
north = float(os.environ.get("HOP_NORTH_M", "10"))
lat = home.latitude * 1e-7 + north / 111195.0
m.mav.command_int_send(m.target_system, 1, M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT,
                       M.MAV_CMD_DO_REPOSITION, 0, 0, -1, 0, 0, 0,
                       int(lat * 1e7), home.longitude, 4.0)
ack = wait(lambda x: x.get_type() == "COMMAND_ACK", "reposition ack")
assert ack.result == M.MAV_RESULT_ACCEPTED, ack
wait(lambda x: x.get_type() == "LOCAL_POSITION_NED" and abs(x.x - north) < 0.5
     and abs(x.vx) < 0.3, f"{north} m north")
command(M.MAV_CMD_DO_SET_HOME, 1, expect=M.MAV_RESULT_UNSUPPORTED)
command(M.MAV_CMD_NAV_LAND)
wait(lambda x: x.get_type() == "EXTENDED_SYS_STATE"
     and x.landed_state == M.MAV_LANDED_STATE_ON_GROUND, "on the ground")
print("landed", flush=True)
