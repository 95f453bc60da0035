"""Misspelled pilot arguments and custom-probe KPIs in budgets get the
did-you-mean treatment, the probe KPI at collection (before anything flies)."""

import pytest

import pytest_flockai as fa
from pytest_flockai.errors import ConfigError


@pytest.mark.parametrize("make, message", [
    (lambda: fa.pilots.Hover(altitdue=5.0),
     "Hover: unknown argument 'altitdue' (did you mean: altitude?); allowed: altitude, "
     "duration, yaw"),
    (lambda: fa.pilots.ZigZag(area=((0, 0), (50, 50)), spaceing=10.0),
     "ZigZag: unknown argument 'spaceing' (did you mean: spacing?)"),
    (lambda: fa.pilots.Orbit(raduis=10.0), "Orbit: unknown argument 'raduis' (did you mean: radius?)"),
    (lambda: fa.pilots.Waypoints([(0, 0, 5)], sped=3.0),
     "Waypoints: unknown argument 'sped' (did you mean: speed?)"),
])
def test_a_misspelled_pilot_argument_suggests_the_right_one(make, message):
    with pytest.raises(ConfigError) as exc:
        make()
    assert message in str(exc.value)


def test_pilots_still_take_their_arguments():
    z = fa.pilots.ZigZag(area=((0, 0), (50, 50)), altitude=20.0, spacing=10.0, speed=5.0)
    assert (z.spacing, z.altitude) == (10.0, 20.0)
    assert fa.pilots.Hover(5.0, 3.0).altitude == 5.0


PROBE_TESTS = '''
import pytest
import pytest_flockai as fa
from pytest_flockai.probes import Metric, Probe


class Counter(Probe):
    name = "app"
    metrics = (Metric("detections_per_min", "1", "detections a minute", better="higher"),)

    def collect(self, view):
        return {"detections_per_min": 3.0}


@pytest.fixture
def probes():
    return [Counter(period_s=1.0)]


@pytest.mark.flockai(drone="crazyflie-2-1", pilot=fa.pilots.Hover(altitude=1.0, duration=1.0))
@pytest.mark.kpi({"app.detections_per_mn": ">= 2"})
def test_typo(flight):
    open("flew.txt", "w").close()


@pytest.mark.flockai(drone="crazyflie-2-1", pilot=fa.pilots.Hover(altitude=1.0, duration=1.0))
@pytest.mark.kpi({"app.detections_per_min": ">= 2"})
def test_right(flight):
    pass
'''


def test_a_misspelled_probe_kpi_in_a_budget_fails_before_the_flight(pytester):
    pytester.makepyfile(test_probe_budget=PROBE_TESTS)
    res = pytester.runpytest_inprocess("-p", "no:cacheprovider")
    res.assert_outcomes(passed=1, errors=1)
    res.stdout.fnmatch_lines(["*budget on 'app.detections_per_mn': probe 'app' has no KPI "
                              "'app.detections_per_mn' (did you mean: app.detections_per_min?)*"])
    assert not (pytester.path / "flew.txt").exists()


BAD_SETTINGS = '''
import pytest

@pytest.mark.flockai(drone="mavic-2")
def test_drone_typo(flight):
    pass

@pytest.mark.flockai(drone="crazyflie-2-1", pilot="hover")
def test_pilot_by_name(flight):
    pass
'''


def test_a_mission_setting_the_core_refuses_is_one_line_naming_the_test(pytester):
    """A misspelled blueprint or a pilot given by name fails at setup with the core's
    message and the test's id, not a traceback into the core."""
    pytester.makepyfile(test_settings=BAD_SETTINGS)
    res = pytester.runpytest_inprocess("-p", "no:cacheprovider")
    res.assert_outcomes(errors=2)
    res.stdout.fnmatch_lines([
        "pytest-flockai: bad mission setting * on test_settings.py::test_drone_typo: unknown "
        "blueprint 'mavic-2' (did you mean: *dji-mavic-2-pro*",
        "pytest-flockai: bad mission setting * on test_settings.py::test_pilot_by_name: Mission: "
        "pilot = 'hover' is not a Pilot*"])
    assert "Traceback" not in res.stdout.str() and "raise ConfigError" not in res.stdout.str()
