"""The telemetry the simulated autopilot streams: which messages, at which rates, and
each message built by pymavlink from one state of the drone (``Autopilot.snapshot``)."""

from __future__ import annotations

from pymavlink.dialects.v20 import common as M

SENSORS = (M.MAV_SYS_STATUS_SENSOR_3D_GYRO | M.MAV_SYS_STATUS_SENSOR_3D_ACCEL
           | M.MAV_SYS_STATUS_SENSOR_3D_MAG | M.MAV_SYS_STATUS_SENSOR_ABSOLUTE_PRESSURE
           | M.MAV_SYS_STATUS_SENSOR_GPS | M.MAV_SYS_STATUS_PREARM_CHECK)
#: telemetry rates (Hz of simulated time) before the app asks for others
RATES = {"ATTITUDE": 10.0, "GLOBAL_POSITION_INT": 10.0, "LOCAL_POSITION_NED": 10.0,
         "SYS_STATUS": 2.0, "EXTENDED_SYS_STATE": 2.0, "BATTERY_STATUS": 1.0,
         "GPS_RAW_INT": 2.0, "HOME_POSITION": 1.0, "MISSION_CURRENT": 1.0}


def message(name: str, s: dict, mission_n: int = 0):
    """Telemetry message ``name`` from the state ``s`` (None: not one streamed);
    ``mission_n``: the mission's length where ``s`` does not carry it."""
    ms = s["ms"]
    if name == "GLOBAL_POSITION_INT":
        m = M.MAVLink_global_position_int_message(
            ms, s["lat"], s["lon"], s["amsl_mm"], s["rel_mm"], s["vn_cm"], s["ve_cm"],
            s["vd_cm"], s["hdg_cdeg"])
    elif name == "LOCAL_POSITION_NED":
        m = M.MAVLink_local_position_ned_message(ms, *s["ned"], *s["vned"])
    elif name == "ATTITUDE":
        m = M.MAVLink_attitude_message(ms, *s["rpy"], *s["rates"])
    elif name == "SYS_STATUS":
        m = M.MAVLink_sys_status_message(SENSORS, SENSORS, SENSORS, 200, s["mv"],
                                         s["ca"], s["pct"], 0, 0, 0, 0, 0, 0)
    elif name == "EXTENDED_SYS_STATE":
        m = M.MAVLink_extended_sys_state_message(M.MAV_VTOL_STATE_UNDEFINED, s["landed"])
    elif name == "BATTERY_STATUS":
        m = M.MAVLink_battery_status_message(
            0, M.MAV_BATTERY_FUNCTION_ALL, M.MAV_BATTERY_TYPE_LIPO, 2500,
            [s["mv"]] + [65535] * 9, s["ca"], -1, -1, s["pct"])
    elif name == "GPS_RAW_INT":
        m = M.MAVLink_gps_raw_int_message(ms * 1000, M.GPS_FIX_TYPE_3D_FIX, s["lat"],
                                          s["lon"], s["amsl_mm"], 100, 150, s["gs_cm"],
                                          s["cog_cdeg"], 12)
    elif name == "HOME_POSITION":
        h = s["home"]
        m = M.MAVLink_home_position_message(h[0], h[1], h[2], 0.0, 0.0, 0.0,
                                            [1.0, 0.0, 0.0, 0.0], 0.0, 0.0, 0.0)
    elif name == "MISSION_CURRENT":
        m = M.MAVLink_mission_current_message(s["mission_seq"],
                                              s.get("mission_n", mission_n))
    else:
        return None
    return m


__all__ = ["RATES", "SENSORS", "message"]
