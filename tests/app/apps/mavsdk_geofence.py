"""MAVSDK-Python program (written for the tests): upload a geofence (an inclusion square
40 m wide around home), set PX4's GF_ACTION from argv[1] (default: leave it), take off to
5 m and fly north in offboard at 3 m/s until the autopilot leaves OFFBOARD (the geofence's
failsafe), print the mode and where it stopped, then land (or, after a return, wait for
the landing). It does not call ``offboard.stop()``: that switches PX4 to HOLD, which would
end a return the failsafe started. With argv[1] "goto" it asks instead for a reposition
40 m north, outside the fence, and prints where the drone is 2 s later, then lands."""

import asyncio
import math
import sys

from mavsdk import System
from mavsdk.geofence import FenceType, GeofenceData, Point, Polygon
from mavsdk.offboard import VelocityNedYaw
from mavsdk.telemetry import FlightMode

M_PER_DEG = math.radians(1.0) * 6371008.8


async def first(stream):
    """The next value of a telemetry stream."""
    async for value in stream:
        return value


async def main():
    drone = System()
    await drone.connect(system_address="udp://:14540")
    async for state in drone.core.connection_state():
        if state.is_connected:
            break
    async for health in drone.telemetry.health():
        if health.is_global_position_ok and health.is_home_position_ok:
            break
    home = await first(drone.telemetry.home())
    goto = sys.argv[1:] == ["goto"]
    if len(sys.argv) > 1 and not goto:
        await drone.param.set_param_int("GF_ACTION", int(sys.argv[1]))
    print("GF_ACTION", await drone.param.get_param_int("GF_ACTION"), flush=True)
    dlat = 20.0 / M_PER_DEG
    dlon = 20.0 / (M_PER_DEG * math.cos(math.radians(home.latitude_deg)))
    square = [Point(home.latitude_deg + a * dlat, home.longitude_deg + b * dlon)
              for a, b in ((-1, -1), (-1, 1), (1, 1), (1, -1))]
    await drone.geofence.upload_geofence(GeofenceData([Polygon(square, FenceType.INCLUSION)], []))
    await drone.action.set_takeoff_altitude(5.0)
    await drone.action.arm()
    await drone.action.takeoff()
    async for pos in drone.telemetry.position():
        if pos.relative_altitude_m > 4.8:
            break
    if goto:                        # a reposition outside the fence: PX4 stays where it is
        await drone.action.goto_location(home.latitude_deg + 40.0 / M_PER_DEG,
                                         home.longitude_deg, home.absolute_altitude_m + 5.0, 0.0)
        await asyncio.sleep(2.0)
        pos = await first(drone.telemetry.position())
        print(f"after goto at {(pos.latitude_deg - home.latitude_deg) * M_PER_DEG:.1f} m "
              f"north of home", flush=True)
        await drone.action.land()
        async for in_air in drone.telemetry.in_air():
            if not in_air:
                break
        print("landed", flush=True)
        return
    await drone.offboard.set_velocity_ned(VelocityNedYaw(3.0, 0.0, 0.0, 0.0))
    await drone.offboard.start()
    async for mode in drone.telemetry.flight_mode():     # the heartbeat's mode (1 Hz)
        if mode == FlightMode.OFFBOARD:
            break
    async for mode in drone.telemetry.flight_mode():
        if mode != FlightMode.OFFBOARD:
            break
    pos = await first(drone.telemetry.position())
    north = (pos.latitude_deg - home.latitude_deg) * M_PER_DEG
    print(f"mode {mode.name} at {north:.1f} m north of home", flush=True)
    if mode == FlightMode.HOLD:
        await drone.action.land()
    async for in_air in drone.telemetry.in_air():
        if not in_air:
            break
    print("landed", flush=True)


asyncio.run(main())
