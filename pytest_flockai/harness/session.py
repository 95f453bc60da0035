"""The session side: options checked once, the per-test entries collected on the
controller (also those xdist workers send), the JSON report and the baseline
file written at the end (atomically, also on failure or interrupt)."""

from __future__ import annotations

import math

import pytest

from .. import report as _report
from . import terminal
from .options import DEFAULT_MAX_REGRESSION, option, path_option

SESSION = pytest.StashKey["FlockSession"]()


class FlockSession:
    """Options, the baseline and the collected per-test data of one pytest run."""

    def __init__(self, config):
        self.config = config
        self.worker = hasattr(config, "workerinput")
        self.tests: dict[str, dict] = {}   # nodeid -> entry (controller only)
        self.json_path = path_option(config, "json")
        self.save_path = path_option(config, "save")
        self.baseline_path = path_option(config, "baseline")
        self.artifacts = path_option(config, "artifacts")
        self.max_regression = DEFAULT_MAX_REGRESSION
        self.baseline = None
        if getattr(config.option, "help", False) or getattr(config.option, "version", False):
            return   # pytest --help must work whatever the options say
        v, _ = option(config, "max-regression")
        try:
            self.max_regression = DEFAULT_MAX_REGRESSION if v is None else float(v)
        except ValueError:
            self.max_regression = math.nan
        if not (self.max_regression >= 0 and math.isfinite(self.max_regression)):
            raise pytest.UsageError(f"--flockai-max-regression = {v!r} is not allowed; "
                                    f"expected a percentage >= 0, e.g. 5")
        try:
            if not self.worker:
                for path, what in ((self.json_path, "--flockai-json"),
                                   (self.save_path, "--flockai-save")):
                    if path is not None:
                        _report.check_writable(path, what)
                if self.artifacts is not None:
                    self.artifacts.mkdir(parents=True, exist_ok=True)
                    _report.check_writable(self.artifacts / "x", "--flockai-artifacts")
            if self.baseline_path is not None:
                self.baseline = _report.load_baseline(self.baseline_path)
        except _report.ReportError as exc:
            raise pytest.UsageError(f"pytest-flockai: {exc}") from None
        except OSError as exc:
            raise pytest.UsageError(f"pytest-flockai: --flockai-artifacts: {exc}") from None

    # -- collecting reports (on the controller: also the ones xdist workers send) --
    def pytest_runtest_logreport(self, report):
        if self.worker:
            return
        payload = getattr(report, "flockai", None)
        entry = self.tests.get(report.nodeid)
        if entry is None:
            if payload is None:
                return
            entry = self.tests[report.nodeid] = {"nodeid": report.nodeid, "outcome": "passed",
                                                 "error": None, "flights": [], "budgets": [],
                                                 "regressions": []}
        if payload is not None:
            entry.update(payload)
        entry["outcome"] = _outcome(entry["outcome"], report)

    def entries(self) -> list[dict]:
        """Per-test entries sorted by nodeid (the same order with or without xdist)."""
        return [self.tests[k] for k in sorted(self.tests)]

    def pytest_sessionfinish(self, session, exitstatus):
        if self.worker:
            return
        interrupted = int(exitstatus) == int(pytest.ExitCode.INTERRUPTED)
        if self.json_path is not None:
            doc = _report.build_report(
                self.entries(), exitstatus=exitstatus, interrupted=interrupted,
                options={"baseline": str(self.baseline_path) if self.baseline_path else None,
                         "max_regression_pct": self.max_regression})
            self.config.hook.pytest_flockai_json_report(report=doc, config=self.config)
            _report.write_json_atomic(self.json_path, doc)
        if self.save_path is not None:
            _report.write_json_atomic(self.save_path, _report.baseline_from_tests(self.entries()))

    def pytest_terminal_summary(self, terminalreporter, exitstatus, config):
        if self.worker:
            return
        files = [f"{what} written to {p}" for what, p in
                 (("JSON report", self.json_path), ("baseline", self.save_path)) if p is not None]
        terminal.summary(terminalreporter, config, self.entries(), files)


def _outcome(prev: str, report) -> str:
    wasxfail = hasattr(report, "wasxfail")
    if report.when == "call":
        if wasxfail:
            return "xpassed" if report.passed else "xfailed"
        return report.outcome
    if report.failed:
        return "error" if prev in ("passed", "skipped") or report.when == "setup" else prev
    if report.skipped and report.when == "setup":
        return "xfailed" if wasxfail else "skipped"
    return prev
