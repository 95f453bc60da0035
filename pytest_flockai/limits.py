"""Resource limits: the largest mission and world pytest-flockai accepts.

Inputs above a limit are refused with a ``ConfigError`` when they enter
(``Mission(...)``, ``World.urban(...)``, the pilots, ``Wind``), before
anything is allocated or flown, so no accepted input allocates more than
about 1 GiB (measured by ``benchmarks/limits.py``). Each limit is a module
attribute read at the moment of the check, so a session that needs more can
raise it, at its own risk::

    import pytest_flockai as fa
    fa.limits.MAX_PEOPLE = 50_000

A flight that is accepted but runs too long on the host is stopped by
``Mission(max_wall_s=...)`` with a ``SimulationError`` carrying the partial
result.
"""

from __future__ import annotations

from .errors import ConfigError

#: s: the largest ``Mission(max_time_s=...)``, the cap on simulated time of one flight
#: (``max_time_s`` defaults to 4 h; a numeric ``until`` must not exceed ``max_time_s``)
MAX_TIME_S = 24 * 3600.0
#: rows of telemetry one flight may record: simulated time x ``telemetry_hz``
#: (13.9 h at the default 10 Hz; the DataFrame at the limit peaks near 0.5 GiB)
MAX_TELEMETRY_ROWS = 500_000
#: samples one probe may record in one flight: simulated time / its ``period_s``
MAX_PROBE_SAMPLES = 250_000
#: m: the longest side of a world (``World.urban``/``World.scene`` ``size``)
MAX_WORLD_SIDE_M = 2_000.0
#: people in a world (scattered plus crowds, or listed). Every articulated figure adds
#: ~120 mesh vertices and ~200 faces to the flight's MuJoCo model, and MuJoCo keeps a
#: bounding-volume hierarchy of every face: at 10,000 people and 2,000 cars a flight
#: peaked at 1.8 GiB (benchmarks/limits.py), at 3,000 and 1,000 at 0.74 GiB
MAX_PEOPLE = 3_000
#: vehicles in a world (~ 0.07 MiB of compiled model each, articulated cars)
MAX_VEHICLES = 1_000
#: points of one ``Waypoints`` pilot (a ZigZag's legs included)
MAX_WAYPOINTS = 100_000
#: m: how far from home (horizontally or in altitude) a pilot may send the drone
#: (a Mavic on one battery covers about 15 km)
MAX_EXTENT_M = 100_000.0
#: variants of one sweep (``fa.sweep``: a grid's combinations, or ``samples``). A variant
#: holds its values and its row of KPIs until the DataFrame is built, ~2.4 KiB each: at the
#: limit a 238 MiB Python peak, 506 MiB RSS with the package loaded (benchmarks/limits.py
#: sweep); a 10 s Crazyflie hover takes ~0.05 s of wall time, so ~40 min on 2 cores
MAX_VARIANTS = 100_000
#: m/s: the strongest mean wind. The strongest gust ever measured at the surface is
#: 113.3 m/s (WMO Archive of Weather and Climate Extremes, Barrow Island, 1996)
MAX_WIND_MPS = 113.0


def check_at_most(field: str, value: float, limit_name: str, *, where: str = "",
                  unit: str = "", how: str = "") -> None:
    """ConfigError naming ``field``, ``value`` and the limit when ``value`` is above it."""
    limit = globals()[limit_name]
    if value > limit:
        pre = f"{where}: " if where else ""
        raise ConfigError(f"{pre}{field} = {value:g}{unit} is above the limit "
                          f"pytest_flockai.limits.{limit_name} = {limit:g}{unit}"
                          f"{'; ' + how if how else ''} (raise the limit at your own risk: "
                          f"fa.limits.{limit_name} = ...)")
