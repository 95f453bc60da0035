"""``flockai compare`` and ``flockai history`` (pytest_flockai/reports): deltas in
each KPI's better direction, the exit status CI reads, the trend across commits."""

import json
import shutil
import subprocess

import pytest

from pytest_flockai import cli
from pytest_flockai.reports import compare as cmp
from pytest_flockai.reports import history


def baseline(path, tests):
    path.write_text(json.dumps({"schema": "pytest-flockai-baseline/1", "tests": tests}))
    return path


BASE = {"t.py::test_a": {"flight": {"endurance_s": 1000.0, "energy_total_j": 5000.0,
                                    "distance_m": 100.0, "crashed": 0.0}},
        "t.py::test_gone": {"flight": {"endurance_s": 1.0}}}


def run(tmp_path, new_tests, *args, capsys=None):
    b = baseline(tmp_path / "base.json", BASE)
    n = baseline(tmp_path / "new.json", new_tests)
    return cli.main(["compare", str(b), str(n), *args])


def test_no_change_exits_0(tmp_path, capsys):
    assert run(tmp_path, {"t.py::test_a": BASE["t.py::test_a"]}) == 0
    out = capsys.readouterr().out
    assert out.startswith("no regression beyond 5%") and "only in the base: t.py::test_gone" in out


def test_a_regression_beyond_the_threshold_exits_1(tmp_path, capsys):
    new = {"t.py::test_a": {"flight": {**BASE["t.py::test_a"]["flight"], "endurance_s": 900.0}}}
    assert run(tmp_path, new) == 1                        # -10 % on a higher-is-better KPI
    out = capsys.readouterr().out
    assert out.startswith("1 regression(s) in 1 test(s) beyond 5%")
    assert "-10.00%" in out and "endurance_s" in out
    assert run(tmp_path, new, "--threshold", "12%") == 0   # within a wider threshold
    out = capsys.readouterr().out
    assert out.startswith("no regression beyond 12%; 1 KPI(s) worse within the threshold")


def test_the_direction_comes_from_the_kpi_registry(tmp_path, capsys):
    """More energy is worse, more endurance is better, distance has no direction."""
    new = {"t.py::test_a": {"flight": {"endurance_s": 1200.0, "energy_total_j": 5600.0,
                                       "distance_m": 300.0, "crashed": 0.0}}}
    assert run(tmp_path, new, "--json", str(tmp_path / "d.json")) == 1
    deltas = {d["kpi"]: d for d in json.loads((tmp_path / "d.json").read_text())["deltas"]}
    assert deltas["endurance_s"]["status"] == "better"
    assert deltas["energy_total_j"]["status"] == "regression"
    assert deltas["energy_total_j"]["change_pct"] == pytest.approx(12.0)
    assert deltas["distance_m"]["status"] == "changed" and deltas["distance_m"]["better"] is None
    assert deltas["crashed"]["status"] == "same"


def test_a_crash_from_zero_is_a_regression():
    better, status = cmp.classify("crashed", 0.0, 1.0, 5.0)
    assert (better, status) == ("lower", "regression")
    assert cmp.classify("crashed", 0.0, 0.0, 5.0)[1] == "same"
    assert cmp.classify("endurance_s", None, 3.0, 5.0)[1] == "n/a"


def test_compare_reads_json_reports_too(tmp_path, capsys):
    report = {"schema": "pytest-flockai/1", "tests": [
        {"nodeid": "t.py::test_a", "flights": [{"name": "flight", "kpis": {"endurance_s": 500.0}}]}]}
    (tmp_path / "r.json").write_text(json.dumps(report))
    b = baseline(tmp_path / "base.json", BASE)
    assert cli.main(["compare", str(b), str(tmp_path / "r.json")]) == 1


def test_bad_input_exits_2_with_a_message(tmp_path, capsys):
    b = baseline(tmp_path / "base.json", BASE)
    (tmp_path / "junk.json").write_text("{not json")
    assert cli.main(["compare", str(b), str(tmp_path / "junk.json")]) == 2
    assert "not valid JSON" in capsys.readouterr().err
    assert cli.main(["compare", str(b), str(tmp_path / "missing.json")]) == 2
    assert cli.main(["compare", str(b), str(b), "--threshold", "lots"]) == 2
    assert "--threshold = 'lots' is not allowed" in capsys.readouterr().err
    with pytest.raises(ValueError):
        cmp.parse_threshold("-3%")


# -- history ---------------------------------------------------------------------------------------
def entries(endurance):
    return [{"nodeid": "t.py::test_a", "flights": [{"name": "flight",
                                                    "kpis": {"endurance_s": endurance}}]}]


def test_history_keeps_each_run_with_its_commit(tmp_path, monkeypatch, capsys):
    d = tmp_path / "hist"
    for commit, value in (("aaaa111", 1000.0), ("bbbb222", 990.0), ("cccc333", 1010.0)):
        monkeypatch.setenv("FLOCKAI_COMMIT", commit)
        history.record(d, entries(value), tmp_path)
    runs = history.load(d)
    assert [r["commit"] for r in runs] == ["aaaa111", "bbbb222", "cccc333"]
    assert history.series(runs, "endurance_s") == {"t.py::test_a / flight": [1000.0, 990.0, 1010.0]}
    assert cli.main(["history", str(d), "--kpi", "endurance_s"]) == 0
    out = capsys.readouterr().out
    assert "endurance_s over 3 run(s)" in out and "bbbb222" in out and "990 s" in out
    pytest.importorskip("matplotlib")
    png = tmp_path / "trend.png"
    assert cli.main(["history", str(d), "--kpi", "endurance_s", "--plot", str(png)]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.skipif(shutil.which("git") is None, reason="git is not installed")
def test_history_takes_the_commit_from_git(tmp_path, monkeypatch):
    monkeypatch.delenv("FLOCKAI_COMMIT", raising=False)
    monkeypatch.delenv("GITHUB_SHA", raising=False)
    assert history.git_info(tmp_path)["commit"] is None       # not a repository
    repo = tmp_path / "repo"
    repo.mkdir()
    git = ["git", "-C", str(repo), "-c", "user.name=t", "-c", "user.email=t@example.com"]
    subprocess.run(git + ["init", "-q"], check=True)
    (repo / "f.txt").write_text("x")
    subprocess.run(git + ["add", "f.txt"], check=True)
    subprocess.run(git + ["commit", "-qm", "one"], check=True)
    head = subprocess.run(git + ["rev-parse", "HEAD"], capture_output=True, text=True).stdout.strip()
    info = history.git_info(repo)
    assert info["commit"] == head and info["dirty"] is False
    (repo / "f.txt").write_text("y")
    assert history.git_info(repo)["dirty"] is True


def test_history_of_a_kpi_no_run_has_exits_2_naming_the_close_ones(tmp_path, capsys):
    history.record(tmp_path / "h", entries(1000.0), tmp_path)
    assert cli.main(["history", str(tmp_path / "h"), "--kpi", "endurnce_s"]) == 2
    err = capsys.readouterr().err
    assert "--kpi 'endurnce_s': no run in" in err and "(did you mean: endurance_s?)" in err
    assert cli.main(["history", str(tmp_path / "h"), "--kpi", "endurance_s", "--test", "nope"]) == 2
    assert "in a test matching --test 'nope'" in capsys.readouterr().err


def test_history_of_a_missing_directory_exits_2(tmp_path, capsys):
    assert cli.main(["history", str(tmp_path / "none"), "--kpi", "endurance_s"]) == 2
    assert "does not exist" in capsys.readouterr().err


def test_the_gate_and_compare_apply_one_rule():
    """The plugin's baseline gate (report.regressions) and ``flockai compare`` call one
    function, so they cannot disagree: a regression in one is one in the other, and a
    family tolerance (``recall`` for ``det.recall``) counts in the gate as in compare."""
    from pytest_flockai import kpis
    from pytest_flockai.reports import files as report

    assert cmp.classify is kpis.classify
    cases = [("energy_total_j", 100.0, v) for v in (100.0, 100.005, 101.0, 104.9, 105.2, 99.0)]
    cases += [("det.recall", 0.8, v) for v in (0.8, 0.79995, 0.77, 0.75, 0.7, 0.9)]
    cases += [("crashed", 0.0, 1.0), ("distance_m", 10.0, 20.0), ("endurance_s", 0.0, 0.0)]
    for pct in (0.0, 5.0):
        for tol in (None, {"recall": 0.06}, {"energy_total_j": 2.0}):
            for kpi, base, new in cases:
                gated = report.regressions({"f": {kpi: new}}, {"f": {kpi: base}}, pct,
                                           abs_tol=tol)
                status = cmp.classify(kpi, base, new, pct, tol)[1]
                assert bool(gated) == (status == "regression"), (kpi, base, new, pct, tol)
    # the family override: 0.8 -> 0.75 is a 6 % drop, tolerated by recall=0.06 in both
    assert report.regressions({"f": {"det.recall": 0.75}}, {"f": {"det.recall": 0.8}}, 5.0)
    assert not report.regressions({"f": {"det.recall": 0.75}}, {"f": {"det.recall": 0.8}}, 5.0,
                                  abs_tol={"recall": 0.06})
