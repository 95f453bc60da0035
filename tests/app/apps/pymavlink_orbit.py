"""A pymavlink program (written for the tests): arm, climb to 5 m, ask for an orbit with
RC-controlled yaw (not emulated: UNSUPPORTED), then DO_ORBIT around the point 10 m east
with radius $ORBIT_RADIUS (6; MAVLink: positive clockwise) and yaw behaviour $ORBIT_YAW
(0: front to the centre); once half a turn is flown around the centre, return to launch
and exit 0 on the ground."""

import math
import os
import sys
import time

from pymavlink import mavutil

url = os.environ.get("FLOCKAI_MAVLINK_URL", "udpin:0.0.0.0:14540").replace("udpin://", "udpin:")
m = mavutil.mavlink_connection(url, source_system=245, source_component=190)
M = mavutil.mavlink
m.wait_heartbeat(timeout=20)
radius = float(os.environ.get("ORBIT_RADIUS", "6"))
yaw_mode = float(os.environ.get("ORBIT_YAW", "0"))


attitude_ms = []                             # time_boot_ms of every ATTITUDE received


def wait(cond, what, timeout=120):
    t0 = time.time()
    while time.time() - t0 < timeout:
        msg = m.recv_match(blocking=True, timeout=1)
        if msg is not None and msg.get_type() == "ATTITUDE":
            attitude_ms.append(msg.time_boot_ms)
        if msg is not None and cond(msg):
            return msg
    sys.exit(f"timed out waiting for {what}")


def command(cmd, *params, expect=M.MAV_RESULT_ACCEPTED):
    p = list(params) + [0.0] * (7 - len(params))
    m.mav.command_long_send(m.target_system, 1, cmd, 0, *p)
    ack = wait(lambda x: x.get_type() == "COMMAND_ACK" and x.command == cmd, f"ack of {cmd}")
    assert ack.result == expect, (cmd, ack.result)


def orbit(yaw, expect=M.MAV_RESULT_ACCEPTED):
    m.mav.command_int_send(m.target_system, 1, M.MAV_FRAME_GLOBAL, M.MAV_CMD_DO_ORBIT, 0, 0,
                           radius, 2.0, yaw, 0, int(home.latitude), int(lon * 1e7),
                           home.altitude * 1e-3 + 5.0)
    ack = wait(lambda x: x.get_type() == "COMMAND_ACK" and x.command == M.MAV_CMD_DO_ORBIT,
               "orbit ack")
    assert ack.result == expect, ack


m.mav.param_set_send(m.target_system, 1, b"MIS_TAKEOFF_ALT", 5.0, M.MAV_PARAM_TYPE_REAL32)
wait(lambda x: x.get_type() == "PARAM_VALUE", "PARAM_VALUE")
home = wait(lambda x: x.get_type() == "HOME_POSITION", "HOME_POSITION")
lon = home.longitude * 1e-7 + 10.0 / (111195.0 * math.cos(math.radians(home.latitude * 1e-7)))
command(M.MAV_CMD_COMPONENT_ARM_DISARM, 1)
command(M.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, math.nan, math.nan, math.nan, math.nan)
wait(lambda x: x.get_type() == "GLOBAL_POSITION_INT" and x.relative_alt > 4800, "5 m")
orbit(M.ORBIT_YAW_BEHAVIOUR_RC_CONTROLLED, expect=M.MAV_RESULT_UNSUPPORTED)
orbit(yaw_mode)
turned, last = 0.0, None
while abs(turned) < math.pi:
    p = wait(lambda x: x.get_type() == "LOCAL_POSITION_NED", "position")
    if abs(math.hypot(p.x, p.y - 10.0) - abs(radius)) > 1.0:
        continue
    a = math.atan2(p.y - 10.0, p.x)          # from north, toward east: clockwise seen from above
    step = 0.0 if last is None else math.remainder(a - last, 2 * math.pi)
    if abs(step) < 0.3:                      # along the circle, not across it (the entry)
        turned += step
    last = a
print("turned", round(math.degrees(turned)), "deg clockwise", flush=True)
span = (attitude_ms[-1] - attitude_ms[0]) / 1000.0
print(f"attitude_hz {(len(attitude_ms) - 1) / span:.2f} over {span:.1f} s", flush=True)
command(M.MAV_CMD_NAV_RETURN_TO_LAUNCH)
wait(lambda x: x.get_type() == "EXTENDED_SYS_STATE"
     and x.landed_state == M.MAV_LANDED_STATE_ON_GROUND, "on the ground")
print("landed", flush=True)
