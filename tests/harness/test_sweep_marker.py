"""@pytest.mark.flockai_sweep with @pytest.mark.kpi: budgets on every variant."""

import json

pytest_plugins = ["pytester"]

TEST = '''
import pytest
import pytest_flockai as fa

pytestmark = pytest.mark.flockai(drone="crazyflie-2-1",
                                 pilot=fa.pilots.Hover(altitude=1.0, duration=1.0))

@pytest.mark.flockai_sweep(payload_kg=[0.0, 0.008], wind_mps=[0.0, 2.0], workers=1)
@pytest.mark.kpi(energy_total_j="<= {limit} J")
def test_envelope(flockai_sweep):
    assert len(flockai_sweep) == 4
'''


def _run(pytester, limit, *args):
    pytester.makepyfile(test_env=TEST.replace("{limit}", str(limit)))
    return pytester.runpytest_inprocess("-p", "no:randomly", "-p", "no:cacheprovider",
                                        "--flockai-json", "r.json", *args)


def test_a_broken_budget_lists_the_variants_that_broke_it(pytester):
    res = _run(pytester, 30)
    res.assert_outcomes(failed=1)
    out = res.stdout.str()
    assert "2 of 4 sweep variant(s) broke a budget" in out
    assert "payload_kg=0.008, wind_mps=0" in out and "payload_kg=0.008, wind_mps=2" in out
    assert "payload_kg=0, wind_mps=0 " not in out       # a passing variant is not listed
    report = json.loads((pytester.path / "r.json").read_text())
    (entry,) = report["tests"]
    sweep = entry["sweep"]
    assert sweep["variants"] == 4 and sweep["broken"] == 2
    assert [r["payload_kg"] for r in sweep["rows"]] == [0.0, 0.0, 0.008, 0.008]
    assert len([b for b in entry["budgets"] if b["verdict"] == "fail"]) == 2


def test_budgets_that_hold_pass_and_the_envelope_is_written(pytester):
    res = _run(pytester, 1000, "--flockai-artifacts", "art")
    res.assert_outcomes(passed=1)
    (csv,) = list((pytester.path / "art").rglob("sweep.csv"))
    assert len(csv.read_text().splitlines()) == 5
    assert list((pytester.path / "art").rglob("sweep.png"))


def test_a_bad_axis_fails_the_test_naming_it(pytester):
    pytester.makepyfile(test_bad='''
import pytest

@pytest.mark.flockai_sweep(paylod_kg=[0.0])
def test_x():
    pass
''')
    res = pytester.runpytest_inprocess("-p", "no:randomly", "-p", "no:cacheprovider")
    res.assert_outcomes(errors=1)
    assert "unknown axis 'paylod_kg'" in res.stdout.str()


def test_a_sweep_without_budgets_is_still_in_the_json_report(pytester):
    pytester.makepyfile(test_nob='''
import pytest
import pytest_flockai as fa

@pytest.mark.flockai(drone="crazyflie-2-1", pilot=fa.pilots.Hover(altitude=1.0, duration=1.0))
@pytest.mark.flockai_sweep(mission_seed=[0, 1], until=[0.5], workers=1)
def test_x(flockai_sweep):
    assert list(flockai_sweep["mission_seed"]) == [0, 1]
''')
    res = pytester.runpytest_inprocess("-p", "no:randomly", "-p", "no:cacheprovider",
                                       "--flockai-json", "r.json")
    res.assert_outcomes(passed=1)
    (entry,) = json.loads((pytester.path / "r.json").read_text())["tests"]
    assert entry["sweep"]["variants"] == 2 and entry["sweep"]["broken"] == 0
    assert "ok" not in entry["sweep"]["rows"][0]
