"""MAVSDK-Python program (written for the tests): wait for a healthy position,
arm, take off to 5 m, hover 3 s, land, wait until on the ground."""

import asyncio

from mavsdk import System


async def main():
    drone = System()
    await drone.connect(system_address="udp://:14540")
    async for state in drone.core.connection_state():
        if state.is_connected:
            break
    async for health in drone.telemetry.health():
        if health.is_global_position_ok and health.is_home_position_ok:
            break
    await drone.action.set_takeoff_altitude(5.0)
    print("takeoff altitude", await drone.action.get_takeoff_altitude(), flush=True)
    await drone.action.arm()
    await drone.action.takeoff()
    async for pos in drone.telemetry.position():
        if pos.relative_altitude_m > 4.8:
            break
    await asyncio.sleep(3)
    await drone.action.land()
    async for in_air in drone.telemetry.in_air():
        if not in_air:
            break
    print("landed", flush=True)


asyncio.run(main())
