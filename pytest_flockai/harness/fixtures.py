"""The provisioning fixtures: ``drone world pilot tasks probes`` (each set by an
indirect parametrization, else the closest ``flockai`` marker, else a default),
``mission`` (assembled, not flown) and ``flight`` (the mission flown)."""

from __future__ import annotations

import dataclasses
import functools
import os
import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest

from ..errors import ConfigError

if TYPE_CHECKING:      # the core loads on first use
    from ..airframe.drone import Drone
    from ..control.pilots import Pilot
    from ..mission import Mission
    from ..result import FlightResult
    from ..world import World

DEFAULT_DRONE = "dji-mavic-2-pro"


def setting(request: pytest.FixtureRequest, key: str, default: Any = None) -> Any:
    """The value for one of the provisioning fixtures: an indirect parametrization
    of that fixture (``@pytest.mark.parametrize("drone", [...], indirect=True)``)
    first, then the closest ``flockai`` marker, then the default."""
    if getattr(request, "fixturename", None) == key and hasattr(request, "param"):
        return request.param
    for mark in request.node.iter_markers("flockai"):   # closest first
        if key in mark.kwargs:
            return mark.kwargs[key]
    return default


@pytest.fixture
def drone(request: pytest.FixtureRequest) -> Drone:
    """A fresh Drone: ``@pytest.mark.flockai(drone=...)`` (a blueprint name, a
    path or a Drone), else ``fa.drone("dji-mavic-2-pro")``."""
    value = setting(request, "drone", DEFAULT_DRONE)
    if isinstance(value, (str, os.PathLike)):
        from ..airframe import drone as make_drone  # lazy: the core loads on first use
        return _built(request, make_drone, value if isinstance(value, str) else Path(value))
    return value


def _built(request, make, *args, **kw):
    """``make(*args, **kw)``; a setting it refuses fails the test in one line naming the
    test, as a bad marker does (no traceback into the core)."""
    try:
        return make(*args, **kw)
    except ConfigError as exc:
        error = str(exc)
    pytest.fail(f"pytest-flockai: bad mission setting (@pytest.mark.flockai or fixture) on "
                f"{request.node.nodeid}: {error}", pytrace=False)


@pytest.fixture
def world(request: pytest.FixtureRequest) -> World | None:
    """The world to fly in: ``@pytest.mark.flockai(world=...)``, else None (empty)."""
    return setting(request, "world", None)


@pytest.fixture
def pilot(request: pytest.FixtureRequest) -> Pilot:
    """The flight plan: ``@pytest.mark.flockai(pilot=...)``, else
    ``fa.pilots.Hover(altitude=10.0, duration=30.0)``."""
    value = setting(request, "pilot", None)
    from ..control.pilots import Hover  # lazy: the core loads on first use
    return Hover(altitude=10.0, duration=30.0) if value is None else value


@pytest.fixture
def tasks(request: pytest.FixtureRequest) -> tuple:
    """ML tasks flown with the mission: ``@pytest.mark.flockai(tasks=...)``, else ()."""
    return tuple(setting(request, "tasks", ()) or ())


@pytest.fixture
def probes(request: pytest.FixtureRequest) -> list | None:
    """Monitoring probes: ``@pytest.mark.flockai(probes=...)``, else None."""
    return setting(request, "probes", None)


@pytest.fixture
def mission(request: pytest.FixtureRequest, drone: Drone, pilot: Pilot, world: World | None,
            tasks: tuple, probes: list | None) -> Mission:
    """The Mission assembled from the fixtures and the ``flockai`` marker (not flown).

    ``pytest_flockai_adjust_mission(mission, item)`` hooks run on it last."""
    from ..mission import Mission  # lazy: the core loads on first use
    m = _built(request, Mission, drone, pilot, world=world, tasks=tasks, probes=probes,
               wind=setting(request, "wind", None), seed=setting(request, "seed", 0),
               until=setting(request, "until", "landed"), name=setting(request, "name", None))
    return adjusted(request.config, m, request.node)


@pytest.fixture
def flight(request: pytest.FixtureRequest, mission: Mission) -> FlightResult:
    """The mission flown: a ``FlightResult`` (recorded for the kpi marker and reports);
    with ``@pytest.mark.flockai_app(cmd=[...], ...)`` the drone flown by that MAVLink
    app instead (``pytest_flockai.app.run``; its output goes into the test's report)."""
    mark = request.node.get_closest_marker("flockai_app")
    if mark is None:
        return mission.run()
    from ..app.launch import marker_flight
    return marker_flight(request, mission, mark)


def adjusted(config: pytest.Config, m: Mission, item: pytest.Item) -> Mission:
    """``m`` after each ``pytest_flockai_adjust_mission`` hook, in pytest's call order,
    each given the spec the one before returned. A hook returns a new spec or None; an
    old hook that assigns fields in place edits a draft copy whose changes are applied
    through ``Mission.replace`` (checked) with a DeprecationWarning."""
    from ..mission import Mission  # lazy: the core loads on first use
    caller = config.hook.pytest_flockai_adjust_mission
    for impl in reversed(caller.get_hookimpls()):
        if getattr(impl, "hookwrapper", False) or getattr(impl, "wrapper", False):
            continue
        cls = _draft_class(Mission)
        draft: Any = object.__new__(cls)   # a copy of m whose fields may be assigned
        draft.__dict__.update(m.__dict__)
        kwargs = {"mission": draft, "item": item}
        out = impl.function(*[kwargs[a] for a in impl.argnames])
        fields = [f.name for f in dataclasses.fields(Mission) if f.init]
        if out is None:
            edits = {f: getattr(draft, f) for f in fields if getattr(draft, f) is not getattr(m, f)}
            if edits:
                warnings.warn(f"pytest_flockai_adjust_mission in {impl.plugin_name}: assigning "
                              f"mission fields in place ({', '.join(edits)}) is deprecated; "
                              f"return mission.replace({', '.join(f'{k}=...' for k in edits)})",
                              DeprecationWarning, stacklevel=1)
                m = m.replace(**edits)
        elif isinstance(out, Mission):
            m = dataclasses.replace(m, **{f: getattr(out, f) for f in fields})
        else:
            raise ConfigError(f"pytest_flockai_adjust_mission in {impl.plugin_name} returned "
                              f"{out!r}; allowed: a Mission (mission.replace(...)) or None")
    return m


@functools.cache
def _draft_class(mission_cls: type) -> type:
    """A Mission subclass whose fields may be assigned (for the deprecated in-place hooks)."""
    def __setattr__(self, name, value):
        object.__setattr__(self, name, value)
    return type("MissionDraft", (mission_cls,), {"__setattr__": __setattr__})

