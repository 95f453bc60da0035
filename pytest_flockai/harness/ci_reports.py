"""The reports people look at, written by the controller at the end of a run:

- ``--flockai-md PATH``: a Markdown summary; also appended to the file named by
  ``GITHUB_STEP_SUMMARY`` (GitHub Actions' job summary) when it is set;
- ``--flockai-html PATH``: the self-contained dashboard; each worker renders its
  flights' pictures (flight path, energy breakdown) and the pictures a test
  attaches with ``record_property("flockai_picture", path)`` (a robustness map,
  say) and sends them with the test report;
- ``--flockai-history DIR``: this run's KPIs with its git commit, for
  ``flockai history``;
- with pytest-html (``--html``): each test's KPI/budget table and pictures as
  extras (``html_extras.py``).
"""

from __future__ import annotations

import base64
import os
import tempfile
from pathlib import Path

import pytest

from .._io import atomic_write
from ..reports import compare as _compare
from ..reports import files as _report
from ..reports import history as _history
from ..reports import html as _html
from ..reports import markdown as _markdown
from ..reports import ml_gallery as _ml_gallery
from . import html_extras as _html_extras
from .options import path_option
from .recorder import STATE
from .session import SESSION

OPTIONS = [
    ("md", "PATH", "write a Markdown summary of the run (budgets broken, regressions, KPI "
                   "table) to PATH; with GITHUB_STEP_SUMMARY set it is also appended there"),
    ("html", "PATH", "write a self-contained HTML dashboard of the run to PATH"),
    ("history", "DIR", "keep this run's KPIs with its git commit in DIR (see flockai history)"),
]
PICTURE_PROPERTY = "flockai_picture"


def add_options(parser) -> None:
    group = parser.getgroup("flockai")
    for name, metavar, help_ in OPTIONS:
        dest = "flockai_" + name
        group.addoption(f"--flockai-{name}", dest=dest, metavar=metavar, default=None, help=help_)
        parser.addini(dest, f"{help_} (ini form of --flockai-{name})", type="string", default="")


class ReportsPlugin:
    def __init__(self, config):
        self.config = config
        self.worker = hasattr(config, "workerinput")
        self.md = path_option(config, "md")
        self.html = path_option(config, "html")
        self.history = path_option(config, "history")
        self.step_summary = os.environ.get("GITHUB_STEP_SUMMARY") or None
        self.written: list[str] = []
        self._pictures: dict[int, list] = {}
        self.pictures: dict[str, list] = {}          # nodeid -> pictures (controller)
        if not self.worker:
            try:
                for p, what in ((self.md, "--flockai-md"), (self.html, "--flockai-html")):
                    if p is not None:
                        _report.check_writable(p, what)
            except _report.ReportError as exc:
                raise pytest.UsageError(f"pytest-flockai: {exc}") from None
        # workers learn from the controller's options (the same command line)
        self.pytest_html = _html_extras.active(config)
        self.want_pictures = self.html is not None or self.pytest_html

    # -- on the workers (or the only process): pictures travel with the test report --
    @pytest.hookimpl(wrapper=True, tryfirst=True)
    def pytest_runtest_makereport(self, item, call):
        report = yield
        if self.want_pictures and call.when == "call":
            pics = self._pictures_of(item)
            if pics and self.html is not None:   # a plain attribute: xdist carries it over
                report.flockai_pictures = pics
            payload = getattr(report, "flockai", None)
            if self.pytest_html and payload is not None:
                _html_extras.add(report, payload, pics)
        return report

    def _pictures_of(self, item) -> list[dict]:
        out = []
        st = item.stash.get(STATE, None)
        for f in (st.flights if st is not None else ()):
            out += self._flight_pictures(f.name, f.result)
        for name, value in item.user_properties:
            if name == PICTURE_PROPERTY:
                title, path = value if isinstance(value, tuple) else (Path(value).stem, value)
                try:
                    data = Path(path).read_bytes()
                except OSError:
                    continue
                out.append({"title": str(title), "data": base64.b64encode(data).decode()})
        return out

    def _flight_pictures(self, name, result) -> list[dict]:
        from .. import plots  # lazy: numpy, and matplotlib (see tests/project/test_architecture.py)
        gallery = _ml_gallery.pictures(name, result)      # drawn with OpenCV, no matplotlib
        if not plots.available():
            return gallery
        key = id(result)
        if key not in self._pictures:
            pics = []
            with tempfile.TemporaryDirectory() as tmp:
                for kind, draw in (("flight path", plots.path_figure),
                                   ("energy", plots.energy_figure)):
                    p = Path(tmp) / "pic.png"
                    draw(result, p)
                    pics.append((kind, base64.b64encode(p.read_bytes()).decode()))
            self._pictures[key] = pics
        return [{"title": f"{name}: {kind}", "data": data}
                for kind, data in self._pictures[key]] + gallery

    # -- on the controller -------------------------------------------------------------------------
    def pytest_runtest_logreport(self, report):
        pics = getattr(report, "flockai_pictures", None)
        if pics and not self.worker:
            self.pictures[report.nodeid] = pics

    def pytest_sessionfinish(self, session, exitstatus):
        if self.worker or not (self.md or self.html or self.history or self.step_summary):
            return
        flock = self.config.stash.get(SESSION, None)
        entries = flock.entries() if flock is not None else []
        interrupted = int(exitstatus) == int(pytest.ExitCode.INTERRUPTED)
        doc = _report.build_report(entries, exitstatus=exitstatus, interrupted=interrupted,
                                   options={"baseline": str(flock.baseline_path)
                                            if flock is not None and flock.baseline_path else None})
        base_scen = _compare.load_scenarios(flock.baseline_path) \
            if flock is not None and flock.baseline_path else None
        if self.md is not None or self.step_summary:
            text = _markdown.job_summary(doc, base_scenarios=base_scen)
            if self.md is not None:
                self._write("Markdown summary", self.md,
                            lambda p: atomic_write(p, lambda fh: fh.write(text)))
            if self.step_summary:
                try:
                    with open(self.step_summary, "a", encoding="utf-8") as fh:
                        fh.write(text)
                    self.written.append("job summary appended to GITHUB_STEP_SUMMARY")
                except OSError as exc:
                    self.written.append(f"GITHUB_STEP_SUMMARY not written: {exc}")
        if self.html is not None:
            self._write("HTML dashboard", self.html, lambda p: _html.write(
                p, doc, pictures=self.pictures, baseline=flock.baseline if flock else None,
                threshold_pct=flock.max_regression if flock else 5.0,
                base_scenarios=base_scen, abs_tol=flock.abs_tol if flock else None,
                pictures_missing=_pictures_missing()))
        if self.history is not None:
            try:
                p = _history.record(self.history, entries, self.config.invocation_params.dir)
                self.written.append(f"KPIs kept in the history as {p}")
            except OSError as exc:
                self.written.append(f"WARNING: history not written to {self.history}: "
                                    f"{exc.strerror or exc}")

    def _write(self, what: str, path, write) -> None:
        """Write one report; a failure (a full disk, its folder gone) is a warning in the
        terminal summary: pytest's exit status stays what the tests made it."""
        try:
            write(path)
        except OSError as exc:
            self.written.append(f"WARNING: the {what} could not be written to {path} "
                                f"({exc.strerror or exc}); the previous file, if any, is "
                                f"left as it was")
            return
        self.written.append(f"{what} written to {path}")

    def pytest_terminal_summary(self, terminalreporter, exitstatus, config):
        for line in self.written:
            warn = line.startswith("WARNING")
            terminalreporter.write_line(f"flockai: {line}", yellow=warn, bold=warn)


def _pictures_missing() -> str | None:
    """Why the dashboard has no flight pictures (matplotlib missing), or None."""
    from .. import plots  # lazy (tests/project/test_architecture.py)
    if plots.available():
        return None
    return ("No flight-path or energy pictures: matplotlib is not installed "
            "(pip install 'pytest-flockai[plots]'); detection galleries need only OpenCV.")
