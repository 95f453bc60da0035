"""A hung app (for the tests): connects, asks for a message the simulated autopilot
does not send (ESTIMATOR_STATUS), starts a child process, then waits forever."""

import os
import subprocess
import sys
import time

from pymavlink import mavutil

m = mavutil.mavlink_connection(os.environ["FLOCKAI_MAVLINK_URL"].replace("udpin://", "udpin:"),
                               source_system=245, source_component=190)
m.wait_heartbeat(timeout=20)
child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(1000)"])
print("child", child.pid, flush=True)
M = mavutil.mavlink
m.mav.command_long_send(1, 1, M.MAV_CMD_REQUEST_MESSAGE, 0,
                        M.MAVLINK_MSG_ID_ESTIMATOR_STATUS, 0, 0, 0, 0, 0, 0)
while True:
    m.recv_match(type="ESTIMATOR_STATUS", blocking=True, timeout=1)
    time.sleep(0.01)
