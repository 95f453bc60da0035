"""The reports tell the story of a run: every collected test with pytest's outcome,
green when pytest passed (xfail budget failures included), the scenario change
before the regressions, one row per KPI family, and no news from float noise."""

import json
import random

import pytest

from pytest_flockai import cli, kpis
from pytest_flockai.reports import compare as cmp
from pytest_flockai.reports import html as dash
from pytest_flockai.reports import markdown

ML_SUITE = '''
import pytest
import pytest_flockai as fa
from pytest_flockai.budgets import check

HOVER = fa.pilots.Hover(altitude=1.0, duration=1.0)


@pytest.mark.flockai(drone="crazyflie-2-1", pilot=HOVER)
@pytest.mark.kpi(crashed="== 0")
def test_hover(flight):
    pass


@pytest.mark.xfail(reason="the model is not good enough yet", strict=True)
@pytest.mark.flockai(drone="crazyflie-2-1", pilot=HOVER)
@pytest.mark.kpi(flight_time_s=">= 1 h", battery_remaining=">= 99.9%")
def test_long_hover_not_there_yet(flight):
    pass


def test_scores_without_flying():
    check({"recall": 0.8, "precision": 0.9}, recall=">= 0.7")


def test_a_budget_the_test_expects_to_break():
    with pytest.raises(AssertionError):
        check({"recall": 0.2}, recall=">= 0.7")


@pytest.mark.skip(reason="no GPU here")
def test_needs_a_gpu():
    pass
'''


def test_a_green_run_with_xfail_budget_failures_is_green(pytester, monkeypatch):
    """The ML team's case: pytest passes (2 passed... 1 xfailed), the two budgets broken in
    the xfail test do not make the dashboard or the job summary red, and every collected
    test is in the JSON, Markdown and HTML reports, with the budgets it checked itself."""
    step = pytester.path / "step.md"
    monkeypatch.setenv("GITHUB_STEP_SUMMARY", str(step))
    pytester.makepyfile(test_team_suite=ML_SUITE)   # not test_ml: tests/ml/test_ml.py may be imported
    res = pytester.runpytest_inprocess("-p", "no:cacheprovider", "--flockai-json", "r.json",
                                       "--flockai-md", "s.md", "--flockai-html", "d.html")
    res.assert_outcomes(passed=3, xfailed=1, skipped=1)
    assert res.ret == 0
    doc = json.loads((pytester.path / "r.json").read_text())
    outcomes = {t["nodeid"].split("::")[-1]: t["outcome"] for t in doc["tests"]}
    assert outcomes == {"test_hover": "passed", "test_long_hover_not_there_yet": "xfailed",
                        "test_scores_without_flying": "passed", "test_needs_a_gpu": "skipped",
                        "test_a_budget_the_test_expects_to_break": "passed"}
    assert doc["summary"] == {"tests": 5, "passed": 3, "xfailed": 1, "skipped": 1, "flights": 2}
    checked = next(t for t in doc["tests"] if t["nodeid"].endswith("without_flying"))
    assert [(b["kpi"], b["verdict"], b["source"]) for b in checked["budgets"]] == [
        ("recall", "pass", "check")]
    md = (pytester.path / "s.md").read_text()
    assert md.startswith("## pytest-flockai: ✅ 5 test(s) (3 passed, 1 skipped, 1 xfailed)")
    assert "### Budgets broken (0)" in md and "❌" not in md
    assert "expected it (xfail, or a check the test expected to fail): 3" in md
    assert all(name in md for name in outcomes)
    assert step.read_text() == md
    page = (pytester.path / "d.html").read_text()
    assert 'id="status" class="ok"' in page and "passed: 5 test(s)" in page
    assert "3 budget(s) broken where expected (2 xfail, 1 caught by pytest.raises)" in page
    tests = [r for r in _rows(page, "tests")]
    assert sorted(r[1].split("::")[-1] for r in tests) == sorted(outcomes)
    assert {r[1].split("::")[-1]: r[0] for r in tests} == outcomes      # verdict first
    broken = _rows(page, "broken")
    assert sorted(r[0] for r in broken) == ["caught", "xfail", "xfail"]


def _rows(page: str, tid: str) -> list[list[str]]:
    import html.parser

    class P(html.parser.HTMLParser):
        rows, cell, inside = [], None, False

        def handle_starttag(self, tag, attrs):
            if tag == "table":
                self.inside = dict(attrs).get("id") == tid
            elif self.inside and tag == "tr":
                self.rows.append([])
            elif self.inside and tag == "td":
                self.cell = ""

        def handle_data(self, data):
            if self.cell is not None:
                self.cell += data

        def handle_endtag(self, tag):
            if tag == "td" and self.cell is not None:
                self.rows[-1].append(self.cell)
                self.cell = None
            elif tag == "table":
                self.inside = False
    p = P()
    p.rows = []
    p.feed(page)
    return [r for r in p.rows if r]


SWAP_SUITE = '''
import os
import pytest
import pytest_flockai as fa
from pytest_flockai.ml import PythonModel

DEVICE = os.environ.get("TEST_DEVICE", "jetson-nano-10w")


def fly(name):
    task = fa.Task(PythonModel(lambda f: 0.0, macs=5e8, name="m"), name="det", period_s=0.5)
    return fa.Mission(drone=fa.drone("dji-mavic-2-pro", device=DEVICE), name=name, tasks=[task],
                      pilot=fa.pilots.Hover(altitude=2.0, duration=1.0)).run()


def test_two_hovers():
    fly("first")
    fly("second")
'''


def test_swapping_the_computer_shows_the_scenario_change_first(pytester, monkeypatch):
    """Jetson Nano -> Pi 4: the compare and the job summary name the change before any
    KPI, and each KPI family is one row however many flights regressed."""
    pytester.makepyfile(test_swap=SWAP_SUITE)
    args = ("-p", "no:cacheprovider", "--flockai-max-regression", "0.5")
    pytester.runpytest_inprocess(*args, "--flockai-json", "base.json",
                                 "--flockai-save", "saved.json").assert_outcomes(passed=1)
    monkeypatch.setenv("TEST_DEVICE", "raspberry-pi-4")
    res = pytester.runpytest_inprocess(*args, "--flockai-json", "new.json", "--flockai-baseline",
                                       "saved.json", "--flockai-md", "s.md",
                                       "--flockai-html", "d.html")
    res.assert_outcomes(failed=1)
    change = "computer: jetson-nano-10w -> raspberry-pi-4"
    res.stdout.fnmatch_lines([f"*  scenario change: {change}",
                              "*flight*KPI family*baseline*actual*change*better*",
                              "*2 flights*inference_latency_p50_s (x4)*+*%*lower*"])
    assert "det.inference_latency_p50_s" not in res.stdout.str()     # the twin is folded
    md = (pytester.path / "s.md").read_text()
    assert change in md and md.index(change) < md.index("### Regressions")
    c = cmp.compare_files(pytester.path / "base.json", pytester.path / "new.json", 0.5)
    assert c.causes == {"test_swap.py::test_two_hovers": [change]}
    groups = c.groups()
    families = [g.family for g in groups]
    assert groups and len(families) == len(set(families))          # one row per family
    assert all(len(g.flights) == 2 and g.cause == change for g in groups)
    assert [g.size for g in groups] == sorted((g.size for g in groups), reverse=True)
    regs = _rows((pytester.path / "d.html").read_text(), "regressions")
    assert len(regs) == len(groups) and all(r[-1] == change for r in regs)


def test_compare_prints_the_scenario_change_before_the_regressions(tmp_path, capsys):
    def report(device, energy):
        return {"schema": "pytest-flockai/1", "tests": [{"nodeid": "t.py::test", "flights": [
            {"name": n, "scenario": {"drone": {"name": "dji-mavic-2-pro", "device": device},
                                     "seed": 0},
             "kpis": {"energy_total_j": energy * k, "det.recall": 0.5, "recall": 0.5}}
            for n, k in (("a", 1.0), ("b", 1.1))]}]}
    (tmp_path / "b.json").write_text(json.dumps(report("jetson-nano-10w", 1000.0)))
    (tmp_path / "n.json").write_text(json.dumps(report("raspberry-pi-4", 1200.0)))
    assert cli.main(["compare", str(tmp_path / "b.json"), str(tmp_path / "n.json")]) == 1
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("1 regression(s) in 1 test(s) beyond 5%")
    assert out[2] == "scenario changes:"
    assert out[3].startswith("  computer: jetson-nano-10w -> raspberry-pi-4  (1 test(s)")
    rows = [line for line in out if "energy_total_j" in line]
    assert len(rows) == 1 and "(x2)" in rows[0] and "+20.00%" in rows[0]


def test_twins_and_drones_fold_into_one_family():
    kpis.register("det.recall", "fraction", "higher")    # as a task's run registers it
    assert cmp.family("det.recall") == "recall" and cmp.family("recall") == "recall"
    assert cmp.family("drone-2.flight_time_s") == "flight_time_s"
    assert cmp.family("fleet.makespan_s") == "fleet.makespan_s"
    assert cmp.family("recall.person") == "recall.person"
    assert cmp.family("det.recall.person") == "recall.person"
    base = {"t": {"f": {"det.recall": 0.8, "recall": 0.8}, "g": {"recall": 0.8}}}
    new = {"t": {"f": {"det.recall": 0.6, "recall": 0.6}, "g": {"recall": 0.7}}}
    (row,) = cmp.compare(base, new).groups()
    assert (row.family, row.count, row.flights, row.worst.new) == ("recall", 3, ("f", "g"), 0.6)


def test_identical_reports_but_float_noise_report_no_change(tmp_path, capsys):
    """+-1e-9 relative noise on every KPI: nothing worse, better or regressed."""
    rng = random.Random(0)
    kpis = {"endurance_s": 1694.2, "energy_total_j": 101234.5, "cpu_utilization": 0.3123,
            "inference_latency_p50_s": 0.2, "crashed": 0.0, "battery_remaining": 0.42,
            "recall": 0.71, "io_time_s": 0.0}
    base = {f"t.py::test_{i}": {"flight": dict(kpis)} for i in range(5)}
    new = {t: {"flight": {k: v * (1 + rng.choice((-1e-9, 1e-9))) for k, v in f["flight"].items()}}
           for t, f in base.items()}
    for name, d in (("b.json", base), ("n.json", new)):
        (tmp_path / name).write_text(json.dumps({"schema": "pytest-flockai-baseline/1",
                                                 "tests": d}))
    assert cli.main(["compare", str(tmp_path / "b.json"), str(tmp_path / "n.json")]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[0] == ("no regression beyond 5%; 0 KPI(s) worse within the "
                                   "threshold, 0 better, 40 unchanged (within each KPI's "
                                   "absolute tolerance)")


def test_absolute_tolerance_from_the_registry_and_overrides():
    # 0.00239 % of a CPU share is noise (registry: 1e-4 for a fraction)
    assert cmp.classify("cpu_utilization", 0.30, 0.30 * 1.0000239, 0.0)[1] == "same"
    assert cmp.classify("cpu_utilization", 0.30, 0.31, 0.0)[1] == "regression"
    # a 1 J change of a 100 J flight is a regression at 0 %, not with energy_total_j=2
    assert cmp.classify("energy_total_j", 100.0, 101.0, 0.0)[1] == "regression"
    assert cmp.classify("energy_total_j", 100.0, 101.0, 0.0, {"energy_total_j": 2})[1] == "same"
    assert cmp.parse_abs_tol(["energy_total_j=2,recall=0.01"]) == {"energy_total_j": 2.0,
                                                                   "recall": 0.01}
    with pytest.raises(ValueError, match="KPI=VALUE"):
        cmp.parse_abs_tol(["energy_total_j"])
    # a misspelled KPI is an error (it would silently tolerate nothing), a custom one is not
    with pytest.raises(ValueError, match=r"unknown KPI 'energy_totl_j' \(did you mean: energy_total_j"):
        cmp.parse_abs_tol(["energy_totl_j=5"])
    assert cmp.parse_abs_tol(["app.detections_per_min=1"]) == {"app.detections_per_min": 1.0}


def test_abs_tol_on_the_command_line_of_compare(tmp_path, capsys):
    for name, v in (("b.json", 100.0), ("n.json", 103.0)):
        (tmp_path / name).write_text(json.dumps({"t": {"f": {"energy_total_j": v}}}))
    args = ["compare", str(tmp_path / "b.json"), str(tmp_path / "n.json"), "--threshold", "1"]
    assert cli.main(args) == 1
    assert cli.main(args + ["--abs-tol", "energy_total_j=5"]) == 0
    assert cli.main(args + ["--abs-tol", "energy_total_j=lots"]) == 2
    assert "KPI=VALUE" in capsys.readouterr().err
    assert cli.main(args + ["--abs-tol", "energy_totl_j=5"]) == 2
    assert "unknown KPI 'energy_totl_j'" in capsys.readouterr().err


def test_the_dashboard_has_a_place_for_more_sections():
    doc = {"exitstatus": 1, "summary": {"tests": 1, "failed": 1},
           "tests": [{"nodeid": "t.py::test", "outcome": "failed"}]}
    dash.add_section("ML gallery", lambda page: f"<p id='gallery'>{len(page.doc['tests'])}</p>")
    try:
        text = dash.dashboard(doc)
        assert text.index("ML gallery") < text.index("Detail per test")
        assert "<p id='gallery'>1</p>" in text and 'id="status" class="bad"' in text
    finally:
        dash.SECTIONS[:] = [s for s in dash.SECTIONS if s[0] != "ML gallery"]
    assert "✅" in markdown.job_summary({"exitstatus": 0, "summary": {"tests": 0}, "tests": []})


def test_the_scenario_summary_names_the_model_by_its_file_hash(tmp_path):
    """What the flight cache key knows of a model (its file), the reports say too."""
    import hashlib

    import pytest_flockai as fa
    from pytest_flockai.reports import scenario

    src = fa.ml.OnnxModel("fixtures/models/crowd_cnn.onnx", name="cnn")
    digest = hashlib.sha256(open(src.path, "rb").read()).hexdigest()
    task = fa.Task(src, period_s=5.0, name="cnn", execution="onboard", device="raspberry-pi-4")
    s = scenario.summary({"drone": {"name": "dji-mavic-2-pro", "device": "none"},
                          "tasks": [task.to_dict()], "seed": 3,
                          "conditions": {"visibility_m": 300.0, "severity": 0}})
    assert s["model"] == f"cnn sha256:{digest[:8]} (onboard)"
    assert s["seed"] == "3" and s["conditions"] == '{"visibility_m":300.0}'
    hover = {"type": "Hover", "altitude": 10.0, "duration": 5.0, "yaw": 0.0}
    assert scenario.summary({"pilot": hover})["pilot"] == "Hover(altitude=10, duration=5, yaw=0)"
    assert scenario.diff(scenario.summary({"pilot": hover}),
                         scenario.summary({"pilot": dict(hover, duration=6.0)})) == [
        "pilot: Hover(altitude=10, duration=5, yaw=0) -> Hover(altitude=10, duration=6, yaw=0)"]
    long = {"type": "Waypoints", "points": [[float(i), 0.0, 10.0] for i in range(40)]}
    a, b = (scenario.summary({"pilot": p})["pilot"] for p in (long, dict(long, speed=3.0)))
    assert a.startswith("Waypoints sha256:") and a != b     # long settings: a hash that differs
    other = dict(s, model="cnn sha256:00000000 (onboard)")
    assert scenario.diff(s, other) == [f"model: cnn sha256:{digest[:8]} (onboard) -> "
                                       f"cnn sha256:00000000 (onboard)"]


GATE_SUITE = '''
import pytest
import pytest_flockai as fa

HOVER = fa.pilots.Hover(altitude=1.0, duration=1.0)


@pytest.mark.flockai(drone="crazyflie-2-1", pilot=HOVER)
def test_plain(flight):
    pass


@pytest.mark.flockai(drone="crazyflie-2-1", pilot=HOVER, abs_tol={"energy_total_j": 1000})
def test_tolerant(flight):
    pass
'''


def test_abs_tolerance_on_the_command_line_and_per_test(pytester):
    """A 3 % energy change at --flockai-max-regression 0: a regression, unless its absolute
    tolerance (the test's marker, or --flockai-abs-tol) covers it."""
    pytester.makepyfile(test_gate=GATE_SUITE)
    args = ["-p", "no:cacheprovider", "--flockai-max-regression", "0"]
    pytester.runpytest_inprocess(*args, "--flockai-save", "b.json").assert_outcomes(passed=2)
    doc = json.loads((pytester.path / "b.json").read_text())
    for t in doc["tests"].values():
        t["flight"]["energy_total_j"] *= 0.97
    (pytester.path / "b.json").write_text(json.dumps(doc))
    res = pytester.runpytest_inprocess(*args, "--flockai-baseline", "b.json")
    res.assert_outcomes(passed=1, failed=1)
    res.stdout.fnmatch_lines(["FAILED test_gate.py::test_plain*"])
    res = pytester.runpytest_inprocess(*args, "--flockai-baseline", "b.json",
                                       "--flockai-abs-tol", "energy_total_j=1000")
    res.assert_outcomes(passed=2)
    res = pytester.runpytest_inprocess(*args, "--flockai-baseline", "b.json",
                                       "--flockai-abs-tol", "energy_total_j")
    assert res.ret == pytest.ExitCode.USAGE_ERROR
    res.stderr.fnmatch_lines(["*--flockai-abs-tol = 'energy_total_j'*KPI=VALUE*"])


def test_a_bad_abs_tol_marker_names_the_field():
    from pytest_flockai.errors import ConfigError
    from pytest_flockai.harness.markers import abs_tol_setting

    assert abs_tol_setting({"energy_total_j": 5}) == (("energy_total_j", 5.0),)
    with pytest.raises(ConfigError, match=r"abs_tol\['energy_total_j'\] = -1"):
        abs_tol_setting({"energy_total_j": -1})
    with pytest.raises(ConfigError, match="unknown KPI 'enrgy_total_j'"):
        abs_tol_setting({"enrgy_total_j": 1})
