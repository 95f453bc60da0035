"""Hypothesis strategies for flight scenarios.

The pattern for a fuzzed budget (no function-scoped fixture per example, so
hypothesis' health checks pass; the failing scenario is shrunk and printed)::

    from hypothesis import given
    import pytest_flockai as fa
    from pytest_flockai import strategies as fst
    from pytest_flockai.budgets import check

    @fst.flight_settings(max_examples=10)       # repeatable in CI, seconds not minutes
    @given(grams=fst.st.integers(0, 500))      # integers shrink to the boundary: 291 g
    def test_endurance_with_payload(grams):
        d = fa.drone("dji-mavic-2-pro", payload_kg=grams / 1000)
        r = fa.Mission(d, fa.pilots.Hover(altitude=5, duration=2)).run()
        check(r, endurance_s=">= 20 min")                 # AssertionError with a table

Each example flies a mission, so ``flight_settings`` leaves out what costs
flights and buys little here: the ``explain`` phase (it re-flies the shrunk
example with every argument varied: measured, 300 s of a 314 s run), the
deadline and the example database (CI starts clean anyway; derandomized runs
draw the same examples).

``missions()`` draws whole missions (drone overrides, pilot, wind, seed).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import Any

from hypothesis import HealthCheck, Phase, settings
from hypothesis import strategies as st
from hypothesis import target as _target
from hypothesis.control import currently_in_test_context

from . import budgets as _budgets
from .airframe.drone import G
from .airframe.drone import drone as _drone
from .control import pilots as _pilots
from .mission import Mission
from .result import FlightResult
from .sensors.conditions import Conditions
from .world.wind import Wind

__all__ = ["FLIGHT_PHASES", "batteries", "conditions", "flight_settings", "hovers", "link_quality",
           "missions", "payloads", "pilot_areas", "seeds", "st", "target_margin", "wind_from", "winds",
           "zigzags"]

#: the phases that fit flights: no ``explain`` (it re-flies the failing example many times)
FLIGHT_PHASES = (Phase.explicit, Phase.reuse, Phase.generate, Phase.target, Phase.shrink)


def flight_settings(max_examples: int = 10, **overrides) -> settings:
    """Hypothesis settings for tests that fly a mission per example (see the
    module docstring): derandomized, no deadline, no database, no explain phase,
    no too-slow health check. ``overrides`` go to ``hypothesis.settings``."""
    kw: dict[str, Any] = dict(max_examples=max_examples, deadline=None, derandomize=True, database=None,
              phases=FLIGHT_PHASES, suppress_health_check=[HealthCheck.too_slow])
    kw.update(overrides)
    return settings(**kw)


def seeds() -> st.SearchStrategy[int]:
    """Mission seeds (any non-negative 32-bit integer)."""
    return st.integers(min_value=0, max_value=2 ** 32 - 1)


def winds(max_speed: float = 12.0, *, gusts: bool = True, vertical: bool = False) -> st.SearchStrategy[Wind]:
    """Wind: a horizontal mean of 0..max_speed m/s from any direction, with gusts
    of 0..20 % of the mean speed (MIL-F-8785C light to moderate turbulence)."""
    return st.builds(wind_from, speed_mps=st.floats(0.0, max_speed),
                     heading_rad=st.floats(0.0, 2 * math.pi),
                     gust_fraction=st.floats(0.0, 0.2) if gusts else st.just(0.0),
                     vertical_mps=st.floats(-1.0, 1.0) if vertical else st.just(0.0))


def wind_from(speed_mps: float, heading_rad: float = 0.0, gust_fraction: float = 0.1,
              vertical_mps: float = 0.0) -> Wind:
    """A Wind blowing towards ``heading_rad`` (0 = east) at ``speed_mps``, gusts
    of ``gust_fraction`` x the speed. Named so failing examples read well."""
    return Wind((speed_mps * math.cos(heading_rad), speed_mps * math.sin(heading_rad), vertical_mps),
                gust_std=gust_fraction * speed_mps)


def conditions(*, max_exposure_s: float = 1 / 15, min_visibility_m: float = 20.0,
               min_sun_elevation_deg: float = 2.0, noise: bool = True,
               max_readout_s: float = 0.0,
               weather: Iterable[str] = ()) -> st.SearchStrategy[Conditions]:
    """Imaging conditions: shutter, sun elevation and haze, and where asked a
    rolling shutter (``max_readout_s`` > 0) and weather (``weather``: names from
    ``sensors.weather.WEATHER``, severities 1-5). Each shrinks towards the ideal
    camera (no blur, overhead sun, clear air, global shutter, no weather), so a
    failure hypothesis finds shrinks to its simplest cause. Sun direction and
    shadows are left out: they need a render per example (draw them yourself)."""
    clear = st.just(math.inf)
    hazy = st.floats(min_visibility_m, 2000.0, allow_nan=False)
    readout = (st.one_of(st.just(0.0), st.floats(1e-3, max_readout_s)) if max_readout_s > 0
               else st.just(0.0))
    wx = st.one_of(st.none(), st.sampled_from(list(weather))) if weather else st.none()
    return st.builds(Conditions,
                     exposure_s=st.one_of(st.just(0.0), st.floats(1 / 4000, max_exposure_s)),
                     sun_elevation_deg=st.one_of(st.just(60.0),
                                                 st.floats(min_sun_elevation_deg, 90.0)),
                     visibility_m=st.one_of(clear, hazy), noise=st.just(noise),
                     readout_s=readout, weather=wx,
                     severity=st.integers(1, 5) if weather else st.just(3))


def batteries(min_mah: float = 1000.0, max_mah: float = 6000.0) -> st.SearchStrategy[float]:
    """Battery capacities in mAh (use as ``fa.drone(name, battery_mah=...)``)."""
    return st.floats(min_mah, max_mah)


def payloads(drone_name: str = "dji-mavic-2-pro", *, min_thrust_to_weight: float = 1.6) -> st.SearchStrategy[float]:
    """Payloads in kg that keep the drone's thrust-to-weight above the given ratio."""
    d = _drone(drone_name)
    max_kg = max(0.0, d.max_thrust_n / (min_thrust_to_weight * G) - d.airframe.mass_kg)
    return st.floats(0.0, max_kg)


def link_quality() -> st.SearchStrategy[dict]:
    """Radio conditions: distance to the ground station (m) and packet loss probability."""
    return st.fixed_dictionaries({"distance_m": st.floats(1.0, 2000.0),
                                  "packet_loss": st.floats(0.0, 0.3)})


def pilot_areas(max_side: float = 300.0, min_side: float = 20.0,
                max_offset: float = 200.0) -> st.SearchStrategy[tuple]:
    """Survey boxes ((x0, y0), (x1, y1)) for ZigZag pilots."""
    def build(x0, y0, w, h):
        return ((x0, y0), (x0 + w, y0 + h))
    return st.builds(build, st.floats(-max_offset, max_offset), st.floats(-max_offset, max_offset),
                     st.floats(min_side, max_side), st.floats(min_side, max_side))


def zigzags(max_side: float = 200.0) -> st.SearchStrategy[_pilots.ZigZag]:
    """ZigZag survey pilots: an area (``pilot_areas``), altitude 10-60 m, line
    spacing 10-40 m and speed 3-12 m/s."""
    return st.builds(lambda area, alt, spacing, speed: _pilots.ZigZag(area, alt, spacing, speed),
                     pilot_areas(max_side=max_side), st.floats(10.0, 60.0), st.floats(10.0, 40.0),
                     st.floats(3.0, 12.0))


def hovers(max_duration: float = 60.0) -> st.SearchStrategy[_pilots.Hover]:
    """Hover pilots: altitude 2-50 m for 1 s to ``max_duration`` s."""
    return st.builds(lambda alt, dur: _pilots.Hover(alt, dur), st.floats(2.0, 50.0),
                     st.floats(1.0, max_duration))


def missions(drone: str = "dji-mavic-2-pro", *, pilots: st.SearchStrategy | None = None,
             wind: bool = True, battery: bool = True, payload: bool = True,
             until: str | float = "landed") -> st.SearchStrategy[Mission]:
    """Whole missions: the named drone with drawn battery and payload, a drawn
    pilot (hovers or zig-zags by default), wind and seed."""
    pilots = pilots if pilots is not None else st.one_of(hovers(30.0), zigzags(120.0))
    d0 = _drone(drone)
    cap = d0.battery.capacity_mah

    def build(pilot, w, mah, kg, seed):
        d = _drone(drone, battery_mah=mah, payload_kg=kg)
        return Mission(d, pilot, wind=w, seed=seed, until=until)
    return st.builds(build, pilots, winds() if wind else st.none(),
                     batteries(0.6 * cap, 1.4 * cap) if battery else st.just(cap),
                     payloads(drone) if payload else st.just(0.0), seeds())


def target_margin(result: FlightResult, budgets: dict | None = None, *,
                  label: str = "worst budget margin", **more: Any) -> float:
    """Tell hypothesis to search towards the worst (lowest) relative budget margin.

    Returns that margin (positive: every budget holds). Outside a hypothesis test
    (a test body called directly) it only returns the margin."""
    verdicts = _budgets.evaluate(result, budgets, **more)
    worst = min(v.rel_margin for v in verdicts)
    if currently_in_test_context():
        _target(-float(worst), label=label)
    return worst
