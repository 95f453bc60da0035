"""pytest plugin (pytest11 entry point ``flockai``).

Fixtures
    ``drone`` (default ``fa.drone("dji-mavic-2-pro")``), ``world`` (None),
    ``pilot`` (``fa.pilots.Hover(altitude=10.0, duration=30.0)``), ``tasks``
    (``()``), ``probes`` (None), ``mission`` (a ``Mission`` assembled from
    those, not flown) and ``flight`` (the mission flown: a ``FlightResult``).
    Override any of them in a conftest.py or a test module, or parametrize them
    indirectly (``@pytest.mark.parametrize("drone", ["crazyflie-2-1"], indirect=True)``).

Markers
    ``@pytest.mark.flockai(drone=..., pilot=..., world=..., tasks=...,
    probes=..., seed=..., until=..., wind=..., name=..., max_regression=...)``:
    quick settings read by the fixtures (``drone`` may be a blueprint name or a
    path); ``max_regression`` (a percent, or ``{kpi: percent}``) overrides
    ``--flockai-max-regression`` for this test.

    ``@pytest.mark.kpi(flight_time_s=">= 24 min", ..., flight=None)``: KPI
    budgets (see ``budgets.py``), checked after the test body against every
    flight the test flew (or only the flight named ``flight``). Dotted custom
    KPIs go in a positional dict: ``@pytest.mark.kpi({"probe.metric": "<= 3"})``.
    Budgets are parsed at collection: a bad one makes the test error at setup,
    before anything flies.

Recording
    Every ``Mission.run()`` inside a test (the ``flight`` fixture or your own
    calls) is recorded for that test through a recording sink the plugin opens
    per test (``pytest_flockai.recording``), also a flight that ended in a
    SimulationError. Names: ``Mission(name=...)``, else the fixture that returned
    the flight, else ``"flight"`` (then ``"flight-2"``, ...), on every path.

Reports
    KPIs travel on the test reports (attribute ``flockai``, plain JSON data, so
    pytest-xdist carries them to the controller), and ``--junitxml`` gets them as
    suite properties ``flockai[<nodeid>].<kpi>`` (``harness/junit.py``: the
    schema allows no testcase properties). Files are written by the controller
    only, also when the run is interrupted (``harness/signals.py``).

Options (each also an ini option, same name with underscores)
    ``--flockai-json PATH``, ``--flockai-save PATH``, ``--flockai-baseline PATH``,
    ``--flockai-max-regression PCT`` (5), ``--flockai-artifacts DIR``,
    ``--flockai-missing-baseline warn|fail``. Path options are safe in the space
    form too (``harness/rootdir.py``).
    Flight cache (``harness/flightcache.py``): ``--flockai-cache MODE``
    (readwrite), ``--flockai-cache-clear``, marker ``flockai_cache(mode)``.
    CI reports (``harness/ci_reports.py``): ``--flockai-md PATH`` (and
    ``GITHUB_STEP_SUMMARY``), ``--flockai-html PATH``, ``--flockai-history DIR``.
"""

from __future__ import annotations

import pytest

from . import hookspecs as _hookspecs
from .harness import ci_reports as _ci_reports
from .harness import examples as _examples
from .harness import flightcache as _flightcache
from .harness import markers as _markers
from .harness import misspelt as _misspelt
from .harness import options as _options
from .harness import rootdir as _rootdir
from .harness import sweeps as _sweeps
from .harness import tracebacks as _tracebacks
from .harness import verdicts as _verdicts
from .harness.fixtures import drone, flight, mission, pilot, probes, tasks, world  # noqa: F401
from .harness.recorder import STATE, TestState
from .harness.session import SESSION, FlockSession
from .harness.sweeps import flockai_sweep, flockai_sweep_executor  # noqa: F401
from .recording import checking, recording


def pytest_addhooks(pluginmanager):
    pluginmanager.add_hookspecs(_hookspecs)


def pytest_addoption(parser):
    _options.add_options(parser)
    _flightcache.add_options(parser)
    _ci_reports.add_options(parser)


@pytest.hookimpl(tryfirst=True)
def pytest_load_initial_conftests(early_config, parser, args):
    _rootdir.redo_setup(early_config, args)   # --flockai-baseline PATH must not move the rootdir


def pytest_make_parametrize_id(config, val, argname):
    return _rootdir.param_id(config, val)   # absolute paths: relative to the rootdir


def pytest_configure(config):
    config.addinivalue_line(
        "markers", "kpi(**budgets, flight=None): KPI budgets such as "
        "flight_time_s='>= 24 min', checked against the flights of this test (pytest-flockai)")
    config.addinivalue_line(
        "markers", "flockai(drone=, pilot=, world=, tasks=, probes=, seed=, until=, wind=, "
        "name=, max_regression=, abs_tol=): quick settings for the pytest-flockai fixtures")
    config.addinivalue_line(
        "markers", "flockai_sweep(**axes, samples=None, method='grid', seed=0, workers=None, "
        "executor=None, batch_size=None, progress=None): "
        "fly a sweep of the mission fixture; kpi budgets are checked on every variant")
    config.addinivalue_line(
        "markers", "flockai_app(cmd=[...], timeout_s=120, speed=1.0, env=None, port=None): "
        "the flight fixture is the drone flown by this MAVLink app (pytest_flockai.app)")
    session = FlockSession(config)   # raises UsageError before anything flies
    _sweeps.configure(config)
    config.stash[SESSION] = session
    config.pluginmanager.register(session, "flockai-session")
    config.pluginmanager.register(_flightcache.CachePlugin(config), "flockai-cache")
    config.pluginmanager.register(_ci_reports.ReportsPlugin(config), "flockai-reports")
    config.pluginmanager.register(_tracebacks.RepairPlugin(), "flockai-tracebacks")
    config.pluginmanager.register(_misspelt.MisspeltMarks(config), "flockai-misspelt")


def pytest_unconfigure(config):
    session = config.stash.get(SESSION, None)
    if session is not None:
        session.close()
        config.pluginmanager.unregister(session)
        del config.stash[SESSION]
    for name in ("flockai-cache", "flockai-reports", "flockai-tracebacks", "flockai-misspelt"):
        extra = config.pluginmanager.get_plugin(name)
        if extra is not None:
            config.pluginmanager.unregister(extra)


def _state(item) -> TestState:
    st = item.stash.get(STATE, None)
    if st is None:
        st = item.stash[STATE] = TestState(item, _markers.parse(item))
    return st


def pytest_collection_modifyitems(session, config, items):
    for item in items:
        _state(item)
        _markers.warn_ignored(item)
        _sweeps.request_fixture(item)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_protocol(item, nextitem):
    st = _state(item)
    with recording(lambda result, m: st.record(m, result)), checking(st.record_check):
        return (yield)


@pytest.hookimpl(tryfirst=True)
def pytest_runtest_setup(item):
    st = _state(item)
    st.reset()                     # each attempt (pytest-rerunfailures) starts clean
    if st.markers.error:
        pytest.fail(st.markers.error, pytrace=False)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_call(item):
    st = _state(item)
    st.adopt_fixture_flights()
    session = item.config.stash[SESSION]
    try:
        with _examples.counted(item, st):
            result = yield
    except BaseException:
        try:                       # for the report only: the body's error wins
            _verdicts.check(item, st, session, body_failed=True)
            st.finish(session.artifacts)
        except Exception:
            pass
        raise
    message = _verdicts.check(item, st, session)
    _sweeps.write_envelope(item, st, session.artifacts)
    st.finish(session.artifacts)
    _verdicts.warn(item, st, session)
    if message:
        pytest.fail(message, pytrace=False)
    return result


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item, call):
    st = item.stash.get(STATE, None)
    report = yield
    if st is not None and (st.flights or st.markers.budgets or st.markers.error
                           or st.hypothesis or st.sweep is not None or st.checks):
        report.flockai = st.payload()
    return report
