"""A pymavlink program (for the tests) that uploads a mission with an item the
simulated drone cannot fly (NAV_LOITER_TURNS) and prints the autopilot's answer."""

import os

from pymavlink import mavutil

m = mavutil.mavlink_connection(os.environ["FLOCKAI_MAVLINK_URL"].replace("udpin://", "udpin:"),
                               source_system=245, source_component=190)
M = mavutil.mavlink
m.wait_heartbeat(timeout=20)
items = [(M.MAV_CMD_NAV_WAYPOINT, 0.0), (M.MAV_CMD_NAV_LOITER_TURNS, 2.0)]
m.mav.mission_count_send(1, 1, len(items), M.MAV_MISSION_TYPE_MISSION)
while True:
    msg = m.recv_match(type=["MISSION_REQUEST_INT", "MISSION_REQUEST", "MISSION_ACK"],
                       blocking=True, timeout=10)
    assert msg is not None, "no answer to the mission upload"
    if msg.get_type() == "MISSION_ACK":
        print("mission ack", M.enums["MAV_MISSION_RESULT"][msg.type].name, flush=True)
        break
    cmd, p1 = items[msg.seq]
    m.mav.mission_item_int_send(1, 1, msg.seq, M.MAV_FRAME_GLOBAL_RELATIVE_ALT_INT, cmd, 0, 1,
                                p1, 0, 0, 0, 473977420, 85455940, 10.0,
                                M.MAV_MISSION_TYPE_MISSION)
