"""The example suite's shared setup: the paper's scenarios, flown once per session.

Default runs are short surveys (about 4 min simulated) gated on
``endurance_s`` (the projected flight time at the mission's mean power);
``--flockai-full`` flies every scenario until the battery is depleted, as the
paper did, and gates ``flight_time_s`` instead.
"""

import pytest
import scenarios


def pytest_addoption(parser):
    parser.addoption("--flockai-full", action="store_true", default=False,
                     help="fly full-endurance missions (until the battery is depleted)")


@pytest.fixture(scope="session")
def full(request):
    return request.config.getoption("--flockai-full")


@pytest.fixture(scope="session")
def models():
    return {"cnn": scenarios.cnn(), "cheap": scenarios.cheap()}


@pytest.fixture(scope="session")
def city():
    return scenarios.world()


def _fly(name, models, city, full):
    return scenarios.mission(name, models, full=full, w=city).run()


def _scenario(name):
    """One session fixture per scenario: a test that uses it has that flight
    recorded for its kpi budgets, the JSON report and JUnit properties."""
    @pytest.fixture(scope="session")
    def fixture(models, city, full):
        return _fly(name, models, city, full)
    fixture.__doc__ = f"Scenario {name} of the paper, flown once per session."
    return fixture


sc_1a = _scenario("1-A")
sc_1b = _scenario("1-B")
sc_2 = _scenario("2")
sc_2slow = _scenario("2-slow")
sc_3b = _scenario("3-B")


@pytest.fixture(scope="session")
def det_city():
    return scenarios.detection_world()


@pytest.fixture(scope="session")
def det_model():
    return scenarios.detector()


def _detection(name):
    @pytest.fixture(scope="session")
    def fixture(det_model, det_city):
        return scenarios.detection_mission(name, det_model, det_city).run()
    fixture.__doc__ = f"The person + vehicle detector, {name}, flown once per session."
    return fixture


det_pi4 = _detection("det-pi4")
det_jetson = _detection("det-jetson")
det_remote = _detection("det-remote")
