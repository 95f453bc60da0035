"""A pymavlink program (for the tests) that exercises the geofence's mission protocol
without flying: upload a fence (an inclusion polygon and an exclusion circle), download it
back, clear it, upload a polygon of two vertices and a rally point (both refused), and set
GF_ACTION as PX4 clients do (an INT32 parameter, byte-wise in the float field). Prints
what the autopilot answered."""

import os
import struct

from pymavlink import mavutil

m = mavutil.mavlink_connection(os.environ["FLOCKAI_MAVLINK_URL"].replace("udpin://", "udpin:"),
                               source_system=245, source_component=190)
M = mavutil.mavlink
FENCE = M.MAV_MISSION_TYPE_FENCE
m.wait_heartbeat(timeout=20)
LAT, LON = 473977420, 85455940
POLY = [(M.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_INCLUSION, 4.0, LAT + dy, LON + dx)
        for dy, dx in ((-2000, -3000), (-2000, 3000), (2000, 3000), (2000, -3000))]
CIRCLE = [(M.MAV_CMD_NAV_FENCE_CIRCLE_EXCLUSION, 5.0, LAT + 500, LON)]


def answer(types):
    msg = m.recv_match(type=types, blocking=True, timeout=10)
    assert msg is not None, f"no answer ({types})"
    return msg


def upload(items, mtype=FENCE):
    m.mav.mission_count_send(1, 1, len(items), mtype)
    while True:
        msg = answer(["MISSION_REQUEST_INT", "MISSION_REQUEST", "MISSION_ACK"])
        if msg.get_type() == "MISSION_ACK":
            return M.enums["MAV_MISSION_RESULT"][msg.type].name
        cmd, p1, lat, lon = items[msg.seq]
        m.mav.mission_item_int_send(1, 1, msg.seq, M.MAV_FRAME_GLOBAL_INT, cmd, 0, 1,
                                    p1, 0, 0, 0, lat, lon, 0.0, mtype)


def download():
    m.mav.mission_request_list_send(1, 1, FENCE)
    n = answer(["MISSION_COUNT"]).count
    out = []
    for seq in range(n):
        m.mav.mission_request_int_send(1, 1, seq, FENCE)
        it = answer(["MISSION_ITEM_INT"])
        out.append((it.command, it.param1, it.x, it.y, it.mission_type))
    return out


print("upload", upload(POLY + CIRCLE), flush=True)
got = download()
assert got == [(c, p, la, lo, FENCE) for c, p, la, lo in POLY + CIRCLE], got
print("download", len(got), "items as uploaded", flush=True)
m.mav.mission_clear_all_send(1, 1, FENCE)
print("clear", M.enums["MAV_MISSION_RESULT"][answer(["MISSION_ACK"]).type].name, flush=True)
print("after clear", len(download()), "items", flush=True)
print("two vertices", upload([(c, 2.0, la, lo) for c, _, la, lo in POLY[:2]]), flush=True)
print("rally", upload([(M.MAV_CMD_NAV_RALLY_POINT, 0.0, LAT, LON)], M.MAV_MISSION_TYPE_RALLY),
      flush=True)
as_float = struct.unpack("<f", struct.pack("<i", 3))[0]
m.mav.param_set_send(1, 1, b"GF_ACTION", as_float, M.MAV_PARAM_TYPE_INT32)
v = answer(["PARAM_VALUE"])
print("GF_ACTION", struct.unpack("<i", struct.pack("<f", v.param_value))[0],
      M.enums["MAV_PARAM_TYPE"][v.param_type].name, flush=True)
