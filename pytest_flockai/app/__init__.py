"""Your real MAVLink app in the loop: ``fa.app.run(cmd, drone, ...)`` flies the
simulated drone with an unchanged MAVSDK-Python, pymavlink (or any MAVLink) program
talking to a simulated PX4-style autopilot, and returns an ``AppResult``
(``exit_code``, ``result``: the ``FlightResult`` with every KPI, ``output``).
See docs/how-to/mavlink-app.md. Needs ``pip install pytest-flockai[app]``."""

try:
    import pymavlink  # noqa: F401  (the autopilot's messages)
except ImportError as exc:        # pragma: no cover - depends on the installed extras
    raise ImportError("pytest_flockai.app needs pymavlink: pip install 'pytest-flockai[app]'") from exc

from .launch import AppError, AppResult, run  # noqa: E402

__all__ = ["AppError", "AppResult", "run"]
