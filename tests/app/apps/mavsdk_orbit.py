"""MAVSDK-Python program (written for the tests): take off, orbit a point 15 m east
at 8 m radius until half a turn is flown, return to launch."""

import asyncio
import math

from mavsdk import System
from mavsdk.action import OrbitYawBehavior


async def main():
    drone = System()
    await drone.connect(system_address="udp://:14540")
    async for state in drone.core.connection_state():
        if state.is_connected:
            break
    async for health in drone.telemetry.health():
        if health.is_global_position_ok and health.is_home_position_ok:
            break
    home = await anext(drone.telemetry.home())
    await drone.action.set_takeoff_altitude(6.0)
    await drone.action.arm()
    await drone.action.takeoff()
    async for pos in drone.telemetry.position():
        if pos.relative_altitude_m > 5.5:
            break
    lon = home.longitude_deg + 15.0 / (111195.0 * math.cos(math.radians(home.latitude_deg)))
    await drone.action.do_orbit(8.0, 3.0, OrbitYawBehavior.HOLD_FRONT_TO_CIRCLE_CENTER,
                                home.latitude_deg, lon, home.absolute_altitude_m + 6.0)
    seen = set()
    async for pv in drone.telemetry.position_velocity_ned():
        p = pv.position
        r = math.hypot(p.north_m, p.east_m - 15.0)
        if abs(r - 8.0) < 1.5:
            seen.add(round(math.degrees(math.atan2(p.north_m, p.east_m - 15.0)) / 45) % 8)
        if len(seen) >= 4:
            break
    print("orbit sectors", sorted(seen), flush=True)
    await drone.action.return_to_launch()
    async for in_air in drone.telemetry.in_air():
        if not in_air:
            break
    print("landed", flush=True)


asyncio.run(main())
