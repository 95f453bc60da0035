"""A hung app (for the tests): connects, asks for a message the simulated autopilot
does not send (ESTIMATOR_STATUS), starts a child process, then waits forever. With
HANG_RAISE=1 it raises instead, after starting a thread that keeps its process alive
(as MAVSDK's server does for an app that raised)."""

import os
import subprocess
import sys
import threading
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
if os.environ.get("HANG_RAISE"):
    threading.Thread(target=time.sleep, args=(1000,)).start()      # not a daemon
    raise RuntimeError("lost the vehicle")
while True:
    m.recv_match(type="ESTIMATOR_STATUS", blocking=True, timeout=1)
    time.sleep(0.01)
