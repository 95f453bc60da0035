"""Sharded runs merge into one report."""

import json

from pytest_flockai.cli import main, merge_reports

TESTS = """
import pytest
import pytest_flockai as fa

@pytest.mark.flockai(drone="crazyflie-2-1", pilot=fa.pilots.Hover(1.0, 0.5))
def test_a(flight):
    assert flight.kpis["crashed"] == 0

@pytest.mark.flockai(drone="crazyflie-2-1", pilot=fa.pilots.Hover(1.5, 0.5), seed=3)
def test_b(flight):
    assert flight.kpis["crashed"] == 0
"""


def test_two_shards_merge_into_the_full_report(pytester, tmp_path):
    pytester.makepyfile(test_shards=TESTS)
    a, b, full = tmp_path / "a.json", tmp_path / "b.json", tmp_path / "full.json"
    pytester.runpytest("-p", "no:cacheprovider", "-k", "test_a", f"--flockai-json={a}").assert_outcomes(passed=1)
    pytester.runpytest("-p", "no:cacheprovider", "-k", "test_b", f"--flockai-json={b}").assert_outcomes(passed=1)
    pytester.runpytest("-p", "no:cacheprovider", f"--flockai-json={full}").assert_outcomes(passed=2)
    out = tmp_path / "merged.json"
    assert main(["merge", str(out), str(a), str(b)]) == 0
    merged, whole = json.loads(out.read_text()), json.loads(full.read_text())
    assert merged["schema"] == whole["schema"] == "pytest-flockai/1"

    def kpis(doc):
        return {t["nodeid"]: [f["kpis"] for f in t["flights"]] for t in doc["tests"]}

    assert kpis(merged) == kpis(whole)
    assert merged["summary"]["tests"] == 2 and merged["summary"]["flights"] == 2


def test_merge_rejects_a_corrupt_input(tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text("{not json")
    assert main(["merge", str(tmp_path / "o.json"), str(bad)]) == 2
    assert "bad.json' is not valid JSON" in capsys.readouterr().err
    other = tmp_path / "other.json"
    other.write_text(json.dumps({"schema": "something-else"}))
    try:
        merge_reports([other])
    except Exception as exc:
        assert "is not a pytest-flockai/1 report" in str(exc)
    else:
        raise AssertionError("no error")
