"""MAVSDK-Python program (written for the tests): offboard velocity setpoints in the body
frame with a yaw rate, as MAVSDK's velocity-body example flies them: take off, hold still,
then fly forward at 2 m/s turning clockwise at 30 deg/s for 4 s (wall time), stop, land.
It prints the heading before and after the turn."""

import asyncio

from mavsdk import System
from mavsdk.offboard import VelocityBodyYawspeed


async def heading(drone):
    async for h in drone.telemetry.heading():
        return h.heading_deg


async def main():
    drone = System()
    await drone.connect(system_address="udp://:14540")
    async for state in drone.core.connection_state():
        if state.is_connected:
            break
    async for health in drone.telemetry.health():
        if health.is_global_position_ok and health.is_home_position_ok:
            break
    await drone.action.arm()
    await drone.action.takeoff()
    async for p in drone.telemetry.position():
        if p.relative_altitude_m > 2.3:
            break
    await drone.offboard.set_velocity_body(VelocityBodyYawspeed(0.0, 0.0, 0.0, 0.0))
    await drone.offboard.start()
    before = await heading(drone)
    print(f"heading before {before:.1f}", flush=True)
    await drone.offboard.set_velocity_body(VelocityBodyYawspeed(2.0, 0.0, 0.0, 30.0))
    await asyncio.sleep(4)
    await drone.offboard.set_velocity_body(VelocityBodyYawspeed(0.0, 0.0, 0.0, 0.0))
    await asyncio.sleep(1)
    after = await heading(drone)
    print(f"heading after {after:.1f}", flush=True)
    await drone.offboard.stop()
    await drone.action.land()
    async for in_air in drone.telemetry.in_air():
        if not in_air:
            break
    print("landed", flush=True)


asyncio.run(main())
