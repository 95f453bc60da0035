"""The session side: options checked once, the per-test entries collected on the
controller (also those xdist workers send), the JSON report and the baseline
file written at the end (atomically, also on failure or interrupt).

A test that started and never finished is reported as ``"interrupted"``
(Ctrl-C, SIGTERM) or ``"crashed"`` (its xdist worker died), with the reason
in ``message``. A report that cannot be written at the end (a full disk, a
folder gone or read-only) is a warning: the tests' verdicts and pytest's
exit status stay what they were, and the old file is left as it was.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import pytest

from ..reports import compare as _compare
from ..reports import files as _report
from ..reports import scenario as _scenario
from . import junit, signals, terminal
from .options import DEFAULT_MAX_REGRESSION, MISSING_BASELINE, option, path_option

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
        self.missing_baseline = "warn"
        self.abs_tol: dict = {}
        self.started: dict[str, str | None] = {}   # nodeid -> None, or why it did not finish
        self.write_errors: list[str] = []
        self.held_signals: list[str] = []
        self.junit = False
        self._sigterm = None
        self._holder = signals.Holder(self.held_signals)
        if getattr(config.option, "help", False) or getattr(config.option, "version", False):
            return   # pytest --help must work whatever the options say
        mb, _ = option(config, "missing-baseline")
        if mb is not None and mb not in MISSING_BASELINE:
            raise pytest.UsageError(f"--flockai-missing-baseline = {mb!r} is not allowed; "
                                    f"allowed: {', '.join(MISSING_BASELINE)}")
        self.missing_baseline = mb or "warn"
        at, _ = option(config, "abs-tol")
        try:
            self.abs_tol = _compare.parse_abs_tol([at] if at else [])
        except ValueError as exc:
            raise pytest.UsageError(f"--flockai-abs-tol = {at!r}: {exc}") from None
        self._check_distinct()
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
        if not self.worker:
            self._sigterm = signals.install_sigterm()

    def _check_distinct(self) -> None:
        """Two report options naming one file would overwrite each other (the JSON
        report, the baseline saved, the Markdown summary, the dashboard, JUnit XML);
        links are followed, so two names of one file are caught too."""
        xml = getattr(self.config.option, "xmlpath", None)
        named = [("--flockai-json", self.json_path), ("--flockai-save", self.save_path),
                 ("--flockai-md", path_option(self.config, "md")),
                 ("--flockai-html", path_option(self.config, "html")),
                 ("--junitxml", Path(os.path.expanduser(xml)) if xml else None)]
        seen: dict = {}
        for what, p in named:
            if p is None:
                continue
            key = os.path.realpath(p)
            if key in seen:
                raise pytest.UsageError(f"pytest-flockai: {what} and {seen[key]} name the same "
                                        f"file {str(p)!r}; give each report its own path")
            seen[key] = what

    def close(self) -> None:
        self._holder.stop()
        signals.restore_sigterm(self._sigterm)

    # -- collecting reports (on the controller: also the ones xdist workers send) --
    def pytest_runtest_logstart(self, nodeid, location):
        if not self.worker:
            self.started[nodeid] = "interrupted"

    def pytest_runtest_logfinish(self, nodeid, location):
        if not self.worker:
            self.started.pop(nodeid, None)

    def pytest_runtest_logreport(self, report):
        if self.worker:
            return
        payload = getattr(report, "flockai", None)
        crashed = report.when not in ("setup", "call", "teardown")   # xdist: "???"
        entry = self.tests.get(report.nodeid)
        if entry is None:      # every test is in the reports, also one that flew nothing
            entry = self.tests[report.nodeid] = _entry(report.nodeid)
        if payload is not None:
            entry.update(payload)
        if crashed:
            self.started.pop(report.nodeid, None)
            entry["outcome"] = "crashed"
            entry["message"] = str(report.longrepr)
            return
        entry["outcome"] = _outcome(entry["outcome"], report)
        if report.failed and entry.get("message") is None:
            entry["message"] = _message(report)

    def entries(self) -> list[dict]:
        """Per-test entries sorted by nodeid (the same order with or without xdist)."""
        return [self.tests[k] for k in sorted(self.tests)]

    @pytest.hookimpl(wrapper=True, tryfirst=True)
    def pytest_sessionfinish(self, session, exitstatus):
        """Around every session-finish hook (xdist's shutdown, JUnit's writer):
        signals held back, the unfinished tests marked, our files written first."""
        if self.worker:
            return (yield)
        self._holder.start()
        try:
            self._finish_tests(session)
            self.junit = junit.add_to_suite(self.config, self.entries())
            self._write_reports(session.exitstatus)
            return (yield)
        finally:
            self._holder.stop()

    @pytest.hookimpl(tryfirst=True)
    def pytest_keyboard_interrupt(self, excinfo):
        """The run is being interrupted: a second Ctrl-C must not cut the reports off."""
        if not self.worker:
            self._holder.start()

    def _finish_tests(self, session) -> None:
        for nodeid, why in self.started.items():
            entry = self.tests.setdefault(nodeid, _entry(nodeid))
            entry["outcome"] = why
            entry["message"] = entry.get("message") or (
                "the run was interrupted (Ctrl-C or SIGTERM) before this test finished")
        self.started = {}

    def _write_reports(self, exitstatus) -> None:
        interrupted = int(exitstatus) == int(pytest.ExitCode.INTERRUPTED)
        if self.json_path is not None:
            doc = _report.build_report(
                self.entries(), exitstatus=exitstatus, interrupted=interrupted,
                options={"baseline": str(self.baseline_path) if self.baseline_path else None,
                         "max_regression_pct": self.max_regression,
                         "missing_baseline": self.missing_baseline})
            self.config.hook.pytest_flockai_json_report(report=doc, config=self.config)
            self._write("JSON report", self.json_path, doc)
        if self.save_path is not None:
            base = _report.baseline_from_tests(self.entries())
            base["scenarios"] = _scenario.of_report({"tests": self.entries()})   # for compare
            self._write("baseline", self.save_path, base)

    def _write(self, what, path, doc) -> None:
        try:
            _report.write_json_atomic(path, doc)
        except OSError as exc:
            self.write_errors.append(f"the {what} could not be written to {path} "
                                     f"({exc.strerror or exc}); the previous file, if any, "
                                     f"is left as it was")

    def pytest_terminal_summary(self, terminalreporter, exitstatus, config):
        if self.worker:
            return
        files = [f"{what} written to {p}" for what, p in
                 (("JSON report", self.json_path), ("baseline", self.save_path))
                 if p is not None and not any(str(p) in e for e in self.write_errors)]
        if getattr(self, "junit", False):
            files.append(junit.NOTE.removeprefix("pytest-flockai: "))
        terminal.summary(terminalreporter, config, self.entries(), files)
        for e in self.write_errors:
            terminalreporter.write_line(f"flockai: WARNING: {e}", yellow=True, bold=True)
        if self.held_signals:
            terminalreporter.write_line(f"flockai: {', '.join(self.held_signals)} received while "
                                        f"the reports were written: held back")


def _entry(nodeid: str) -> dict:
    return {"nodeid": nodeid, "outcome": "passed", "error": None, "message": None,
            "flights": [], "budgets": [], "regressions": []}


def _message(report) -> str | None:
    """The one-line reason of a failed report (e.g. pytest-timeout's)."""
    crash = getattr(report.longrepr, "reprcrash", None)
    if crash is not None:
        return crash.message
    text = str(report.longrepr or "").strip().splitlines()
    return text[-1] if text else None


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
