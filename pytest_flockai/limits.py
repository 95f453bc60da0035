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

__all__ = ["MAX_TIME_S", "MAX_TELEMETRY_ROWS", "MAX_PROBE_SAMPLES", "MAX_WORLD_SIDE_M",
           "MAX_PEOPLE", "MAX_VEHICLES", "MAX_WAYPOINTS", "MAX_EXTENT_M", "MAX_VARIANTS",
           "MAX_WIND_MPS", "MAX_CACHE_ENTRY_BYTES", "MAX_CACHE_UNPACKED_BYTES",
           "MAX_CACHE_BYTES", "MIN_ENERGY_HZ", "MIN_VERTICAL_SPEED_MPS", "MAX_SPEED_MPS",
           "MIN_TASK_PERIOD_S", "MAX_JSON_DEPTH"]

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
#: moving actors of one mission (``fa.actors``: people, cars and markers; ``walkers(n)``,
#: ``traffic(n)`` are checked before a path is drawn). Each adds mesh geoms to the flight's
#: MuJoCo model as a world's person does (MAX_PEOPLE), and each frame's object truth tests
#: every actor in view: at 3,000 walkers all in one 90-degree view, 0.74 s and a 154 MiB
#: peak per frame (tests/project/test_reliability_round3.py, the grid-culled occlusion test)
MAX_ACTORS = 3_000
#: mean spurious boxes per frame of an ``Oracle(false_positives=...)``: drawn per frame,
#: each a detection row. Detectors cap their output well below it (COCO's evaluation
#: keeps maxDets = 100 per image; Ultralytics YOLO's predict default max_det = 300)
MAX_ORACLE_FALSE_POSITIVES = 1_000.0
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
#: bytes: the largest flight-cache entry file read (a bigger one is refused unread, as
#: is anything but a regular file); a flight at MAX_TELEMETRY_ROWS packs to ~100 MiB
MAX_CACHE_ENTRY_BYTES = 512 * 2**20
#: bytes: the most a cache entry may unpack to, summed over its arrays, checked on the
#: sizes the entry declares before anything is decompressed (a "zip bomb" is refused)
MAX_CACHE_UNPACKED_BYTES = 1024 * 2**20
#: bytes: the flight cache's size on disk; past it, the least recently used entries are
#: removed after a write (``flockai cache prune`` does the same by hand)
MAX_CACHE_BYTES = 2 * 2**30
#: Hz: the slowest ``Mission(energy_hz=...)``. The energy integrator holds each power
#: sample for one period: at 1 Hz a 50 s Mavic flight's energy is within 0.3 % of 200 Hz,
#: at 0.5 Hz 0.8 % low, at 0.1 Hz 4.8 % low (benchmarks/limits.py ``rates``)
MIN_ENERGY_HZ = 1.0
#: m/s: the slowest ``Mission(climb_speed=..., descent_speed=...)``: slower, a 30 m climb
#: takes over 5 min and a drone that never leaves the ground looks like one still climbing
MIN_VERTICAL_SPEED_MPS = 0.1
#: m/s: the fastest speed a pilot may ask. The fastest quadcopter flown reached 480.2 km/h
#: = 133 m/s (Guinness World Records, "fastest battery-powered remote-controlled
#: quadcopter", 2024). Below it, a speed above the drone's own top speed (its drag at its
#: tilt limit) is flown at that top speed and the flight logs a ``speed_capped`` event
MAX_SPEED_MPS = 150.0
#: s: the shortest ``Task(period_s=...)``. A task runs at most once per inference: with a
#: period shorter than the model's latency it runs back to back (``inference_count`` says
#: how often it ran); shorter than 1 ms is faster than any camera frame rate
MIN_TASK_PERIOD_S = 1e-3
#: nesting depth of a JSON report, baseline or history record (deeper is refused)
MAX_JSON_DEPTH = 64


def check_at_least(field: str, value: float, limit_name: str, *, where: str = "",
                   unit: str = "", how: str = "") -> None:
    """ConfigError naming ``field``, ``value`` and the limit when ``value`` is below it."""
    limit = globals()[limit_name]
    if value < limit:
        pre = f"{where}: " if where else ""
        raise ConfigError(f"{pre}{field} = {value:g}{unit} is below the limit "
                          f"pytest_flockai.limits.{limit_name} = {limit:g}{unit}"
                          f"{'; ' + how if how else ''} (lower the limit at your own risk: "
                          f"fa.limits.{limit_name} = ...)")


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
