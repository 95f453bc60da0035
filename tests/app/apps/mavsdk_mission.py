"""MAVSDK-Python program (written for the tests): upload a 3-waypoint mission with a
speed change and return to launch, download it back, fly it, wait for the landing.
Driven by vehicle events only (no timers): safe to speed up."""

import asyncio
import os

from mavsdk import System
from mavsdk.mission import MissionItem, MissionPlan

LAT, LON = 47.397742, 8.545594
M_LAT = 111195.0


def item(north, east, alt, speed):
    import math
    return MissionItem(LAT + north / M_LAT, LON + east / (M_LAT * math.cos(math.radians(LAT))),
                       alt, speed, True, float("nan"), float("nan"),
                       MissionItem.CameraAction.NONE, float("nan"), float("nan"),
                       float("nan"), float("nan"), float("nan"), MissionItem.VehicleAction.NONE)


async def main():
    drone = System()
    await drone.connect(system_address="udp://:14540")
    async for state in drone.core.connection_state():
        if state.is_connected:
            break
    async for health in drone.telemetry.health():
        if health.is_global_position_ok and health.is_home_position_ok:
            break
    north = float(os.environ.get("MISSION_NORTH_M", "20"))
    plan = MissionPlan([item(north, 0, 10, 5), item(north, 15, 10, 3), item(0, 15, 8, 5)])
    await drone.mission.set_return_to_launch_after_mission(True)
    await drone.mission.clear_mission()
    await drone.mission.upload_mission(plan)
    back = await drone.mission.download_mission()
    assert len(back.mission_items) == 3, back
    await drone.action.arm()
    await drone.mission.start_mission()
    async for progress in drone.mission.mission_progress():
        print(f"mission {progress.current}/{progress.total}", flush=True)
        if progress.current == progress.total:
            break
    was_in_air = False
    async for in_air in drone.telemetry.in_air():
        was_in_air = was_in_air or in_air
        if was_in_air and not in_air:
            break
    print("landed", flush=True)


asyncio.run(main())
