"""Hooks that users of pytest-flockai may implement (in a conftest.py or a plugin).

All hooks of the plugin live here; the plugin registers them with
``pluginmanager.add_hookspecs`` in ``pytest_addhooks``.
"""

from __future__ import annotations

import pytest


@pytest.hookspec
def pytest_flockai_adjust_mission(mission, item):
    """Adjust the Mission built by the ``mission`` fixture before it is flown.

    Called once per test that uses the ``mission`` (or ``flight``) fixture,
    after the fixtures and the ``flockai`` marker have been applied. The mission
    is a frozen spec: return a changed copy (``mission.replace(seed=42,
    until=60.0)``, checked like a new Mission), or None to keep it. Several
    hooks run in pytest's order, each given the spec the one before returned.
    A hook that assigns fields in place (``mission.seed = 42``) and returns None
    still works, with a ``DeprecationWarning``: its changes go through
    ``replace`` and are checked.

    :param mission: the ``pytest_flockai.Mission`` about to be returned.
    :param item: the pytest test item.
    """


@pytest.hookspec
def pytest_flockai_derived_kpis(result, item):
    """Return extra KPIs (``{name: number}``) computed from a flown mission.

    Called for every flight recorded during a test (the ``flight`` fixture or
    any ``Mission.run()`` inside the test). The returned values are merged into
    ``result.kpis`` so budgets, reports and baselines see them. Names should be
    registered KPIs (``pytest_flockai.kpis.register``), custom ones written
    ``<probe>.<metric>``. Return None to add nothing.

    :param result: the ``FlightResult``.
    :param item: the pytest test item.
    """


@pytest.hookspec
def pytest_flockai_json_report(report, config):
    """Inspect or extend the JSON report (a dict, schema ``pytest-flockai/1``)
    just before it is written, on the controller process. Modify it in place.

    :param report: the report dict (see ``pytest_flockai.reports.files``).
    :param config: the pytest config.
    """
