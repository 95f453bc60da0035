"""MAVSDK-Python program (written for the tests): offboard position setpoints in NED
with a heading: a 10 m square at 6 m, facing each leg, then land."""

import asyncio

from mavsdk import System
from mavsdk.offboard import PositionNedYaw


async def main():
    drone = System()
    await drone.connect(system_address="udp://:14540")
    async for state in drone.core.connection_state():
        if state.is_connected:
            break
    async for health in drone.telemetry.health():
        if health.is_local_position_ok:
            break
    await drone.action.arm()
    await drone.offboard.set_position_ned(PositionNedYaw(0.0, 0.0, 0.0, 0.0))
    await drone.offboard.start()
    for n, e, yaw in ((0, 0, 0), (10, 0, 0), (10, 10, 90), (0, 10, 180), (0, 0, 270)):
        await drone.offboard.set_position_ned(PositionNedYaw(n, e, -6.0, yaw))
        async for pv in drone.telemetry.position_velocity_ned():
            p = pv.position
            if abs(p.north_m - n) < 0.5 and abs(p.east_m - e) < 0.5 and abs(p.down_m + 6) < 0.5:
                break
            await drone.offboard.set_position_ned(PositionNedYaw(n, e, -6.0, yaw))
        async for att in drone.telemetry.heading():
            if abs((att.heading_deg - yaw + 180) % 360 - 180) < 10:
                break
            await drone.offboard.set_position_ned(PositionNedYaw(n, e, -6.0, yaw))
        print(f"at {n} N {e} E heading {yaw}", flush=True)
    await drone.offboard.stop()
    await drone.action.land()
    async for in_air in drone.telemetry.in_air():
        if not in_air:
            break
    print("landed", flush=True)


asyncio.run(main())
