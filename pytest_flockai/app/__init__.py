"""Your real MAVLink app in the loop: ``fa.app.run(cmd, drone, ...)`` flies the
simulated drone with an unchanged MAVSDK-Python, pymavlink (or any MAVLink) program
talking to a simulated PX4-style autopilot, and returns an ``AppResult``
(``exit_code``, ``result``: the ``FlightResult`` with every KPI, ``output``).
See docs/how-to/mavlink-app.md. Needs ``pip install pytest-flockai[app]``."""

from .runner import AppError, AppResult, run

__all__ = ["AppError", "AppResult", "run"]
