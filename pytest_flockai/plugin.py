"""pytest plugin (pytest11 entry point ``flockai``).

Fixtures
    ``drone`` (default ``fa.drone("dji-mavic-2-pro")``), ``world`` (None),
    ``pilot`` (``fa.pilots.Hover(altitude=10.0, duration=30.0)``), ``tasks``
    (``()``), ``probes`` (None), ``mission`` (a ``Mission`` assembled from
    those, not flown) and ``flight`` (the mission flown: a ``FlightResult``).
    Override any of them in a conftest.py or a test module, or parametrize them
    indirectly (``@pytest.mark.parametrize("drone", ["crazyflie-2-1"], indirect=True)``).

Markers
    ``@pytest.mark.flockai(drone=..., pilot=..., world=..., tasks=...,
    probes=..., seed=..., until=..., wind=..., name=..., max_regression=...)``:
    quick settings read by the fixtures (``drone`` may be a blueprint name or a
    path); ``max_regression`` (a percent, or ``{kpi: percent}``) overrides
    ``--flockai-max-regression`` for this test.

    ``@pytest.mark.kpi(flight_time_s=">= 24 min", ..., flight=None)``: KPI
    budgets (see ``budgets.py``), checked after the test body against every
    flight the test flew (or only the flight named ``flight``). Dotted custom
    KPIs go in a positional dict: ``@pytest.mark.kpi({"probe.metric": "<= 3"})``.
    Budgets are parsed at collection: a bad one makes the test error at setup,
    before anything flies.

Recording
    Every ``Mission.run()`` inside a test (the ``flight`` fixture or your own
    calls) is recorded for that test, named ``mission.name`` or ``"flight"``
    (then ``"flight-2"``, ... for repeats), through the core's flight observers
    (also a flight that ended in a SimulationError); outside a test nothing is recorded.

Reports
    KPIs travel on the test reports (attribute ``flockai``, plain JSON data, so
    pytest-xdist carries them to the controller) and as ``user_properties``
    ``flockai.<kpi>`` (``flockai.<flight>.<kpi>`` with several flights) so
    ``--junitxml`` shows them. Files are written by the controller only.

Options (each also an ini option, same name with underscores)
    ``--flockai-json PATH``, ``--flockai-save PATH``, ``--flockai-baseline PATH``,
    ``--flockai-max-regression PCT`` (5), ``--flockai-artifacts DIR``.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from . import budgets as _budgets
from . import hookspecs as _hookspecs
from . import kpis as _kpis
from . import report as _report
from .airframe import drone as _make_drone
from .control.pilots import Hover as _Hover
from .errors import ConfigError, close_matches
from .mission import Mission
from .recording import recording
from .result import FlightResult

# ---------------------------------------------------------------------------
# options
# ---------------------------------------------------------------------------
_OPTIONS = [
    # (name, metavar, help)
    ("json", "PATH", "write a JSON report of every flight, KPI and budget (schema "
                     "pytest-flockai/1) to PATH, also when tests fail"),
    ("save", "PATH", "save the KPIs of this run as a baseline file at PATH"),
    ("baseline", "PATH", "compare each test's KPIs with the baseline file PATH (from "
                         "--flockai-save or --flockai-json); a test fails when a KPI is "
                         "worse than its baseline by more than --flockai-max-regression"),
    ("max-regression", "PCT", "largest allowed regression against the baseline, in percent "
                              "of the baseline value, in each KPI's better direction "
                              "(default: 5)"),
    ("artifacts", "DIR", "write each flight's telemetry (CSV) and result (JSON) under "
                         "DIR/<test nodeid>/"),
]
DEFAULT_MAX_REGRESSION = 5.0

FLOCKAI_MARKER_KEYS = ("drone", "pilot", "world", "tasks", "probes", "seed", "until", "wind", "name",
                       "max_regression")
DEFAULT_DRONE = "dji-mavic-2-pro"
HEADLINE_KPIS = ("flight_time_s", "energy_total_j", "mean_power_w", "battery_remaining",
                 "inference_latency_p50_s")


def pytest_addhooks(pluginmanager):
    pluginmanager.add_hookspecs(_hookspecs)


def pytest_addoption(parser):
    group = parser.getgroup("flockai", "pytest-flockai: simulated drone flights and KPI budgets")
    for name, metavar, help_ in _OPTIONS:
        dest = "flockai_" + name.replace("-", "_")
        group.addoption(f"--flockai-{name}", dest=dest, metavar=metavar, default=None,
                        help=help_)
        parser.addini(dest, f"{help_} (ini form of --flockai-{name})", type="string", default="")


def _option(config, name: str):
    """(value, is_from_ini) of an option: the command line wins over the ini file."""
    dest = "flockai_" + name.replace("-", "_")
    v = config.getoption(dest, None)
    if v not in (None, ""):
        return v, False
    v = config.getini(dest)
    return (v if v not in (None, "") else None), True


def _path_option(config, name: str) -> Path | None:
    v, from_ini = _option(config, name)
    if v is None:
        return None
    p = Path(os.path.expanduser(str(v)))
    if not p.is_absolute():
        if from_ini and config.inipath is not None:
            base = config.inipath.parent
        else:
            base = config.invocation_params.dir
        p = base / p
    return p


# ---------------------------------------------------------------------------
# per-test state and the Mission.run recorder
# ---------------------------------------------------------------------------
@dataclass
class Flight:
    name: str
    result: object  # FlightResult

    @property
    def kpis(self) -> dict:
        return self.result.kpis


@dataclass
class TestState:
    """What the plugin knows about one test (kept in ``item.stash``)."""

    item: object
    budgets: list = field(default_factory=list)       # [(flight name or None, Budget)]
    error: str | None = None                           # a bad marker, found at collection
    flights: list = field(default_factory=list)       # [Flight]
    verdicts: list = field(default_factory=list)      # budget rows (dicts)
    regressions: list = field(default_factory=list)
    max_regression: object = None                      # per-test override: % or {kpi: %}
    problems: list = field(default_factory=list)      # kpi marker misuse found after the body
    _props: list = field(default_factory=list)        # user_properties we added

    __test__ = False  # not a pytest test class

    def record(self, mission, result, name: str | None = None):
        base = str(name or getattr(mission, "name", None) or "flight")
        taken = {f.name for f in self.flights}
        name, k = base, 1
        while name in taken:
            k += 1
            name = f"{base}-{k}"
        item = self.item
        for extra in item.config.hook.pytest_flockai_derived_kpis(result=result, item=item):
            if not extra:
                continue
            if not isinstance(extra, dict):
                raise ConfigError(f"pytest_flockai_derived_kpis returned {extra!r}; expected a "
                                  f"dict {{kpi name: number}} or None")
            for key, value in extra.items():
                if not isinstance(key, str) or isinstance(value, bool) or not isinstance(
                        value, (int, float)) and not hasattr(value, "__float__"):
                    raise ConfigError(f"pytest_flockai_derived_kpis: {key!r} = {value!r} is not "
                                      f"allowed; expected a str name and a number")
                result.kpis[key] = float(value)
        self.flights.append(Flight(name, result))
        art = item.config.stash[_SESSION].artifacts
        if art is not None:
            _report.write_artifacts(art, item.nodeid, name, result)

    def payload(self) -> dict:
        """Plain JSON data for the test report (travels through pytest-xdist)."""
        flights = []
        for f in self.flights:
            r = f.result
            flights.append({"name": f.name, "end_reason": getattr(r, "end_reason", None),
                            "sim_time_s": r.scenario.get("sim_time_s"),
                            "scenario": r.scenario, "kpis": r.kpis})
        return _report.jsonable({"flights": flights, "budgets": self.verdicts,
                                 "regressions": self.regressions,
                                 "error": self.error or ("\n".join(self.problems) or None)})


_STATE = pytest.StashKey[TestState]()


def _state(item) -> TestState:
    st = item.stash.get(_STATE, None)
    if st is None:
        st = item.stash[_STATE] = TestState(item)
        _parse_markers(item, st)
    return st


# ---------------------------------------------------------------------------
# session state (one per config)
# ---------------------------------------------------------------------------
class FlockSession:
    """Options, the baseline and the collected per-test data of one pytest run."""

    def __init__(self, config):
        self.config = config
        self.worker = hasattr(config, "workerinput")
        self.tests: dict[str, dict] = {}   # nodeid -> entry (controller only)
        self.json_path = _path_option(config, "json")
        self.save_path = _path_option(config, "save")
        self.baseline_path = _path_option(config, "baseline")
        self.artifacts = _path_option(config, "artifacts")
        self.max_regression = DEFAULT_MAX_REGRESSION
        self.baseline = None
        if getattr(config.option, "help", False) or getattr(config.option, "version", False):
            return   # pytest --help must work whatever the options say
        v, _ = _option(config, "max-regression")
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
        entries = [e for e in self.entries() if e["flights"] or e["budgets"] or e["error"]]
        tr = terminalreporter
        files = [f"{what} written to {p}" for what, p in
                 (("JSON report", self.json_path), ("baseline", self.save_path)) if p is not None]
        if not entries and not files:
            return
        verbose = config.get_verbosity() > 0
        if config.get_verbosity() < 0:
            n = sum(len(e["flights"]) for e in entries)
            tr.write_line(f"flockai: {n} flight(s) in {len(entries)} test(s)"
                          + "".join(f"; {f}" for f in files))
            return
        tr.section("flockai KPIs")
        for e in entries:
            budgets = e["budgets"]
            broken = [b for b in budgets if b["verdict"] != "pass"]
            status = e["outcome"] + (f", {len(broken)} budget(s) broken" if broken else "") + (
                f", {len(e['regressions'])} regression(s)" if e["regressions"] else "")
            tr.write_line(f"{e['nodeid']} ({status})")
            for f in e["flights"]:
                kp = f["kpis"]
                if verbose:
                    rows = [[k, _report.format_kpi(k, v), _better(k)] for k, v in kp.items()]
                    tr.write_line(f"  flight {f['name']!r}: {f.get('end_reason')}, "
                                  f"drone {_drone_name(f)}")
                    tr.write_line(_report.table(["KPI", "value", "better"], rows, indent="    "))
                else:
                    names = [k for k in HEADLINE_KPIS if k in kp]
                    names += [b["kpi"] for b in budgets
                              if b["kpi"] in kp and b["kpi"] not in names]
                    cells = "  ".join(f"{k}={_report.format_kpi(k, kp[k])}" for k in names)
                    tr.write_line(f"  {f['name']}: {cells}")
            if verbose and budgets:
                tr.write_line(_budget_table(budgets, indent="    "))
        for line in files:
            tr.write_line(f"flockai: {line}")


_SESSION = pytest.StashKey[FlockSession]()


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


def _better(kpi):
    info = _kpis.get(kpi)
    return (info.better or "") if info is not None else ""


def _drone_name(flight: dict):
    d = (flight.get("scenario") or {}).get("drone")
    if isinstance(d, dict):
        return d.get("name", "?")
    return str(d)


# ---------------------------------------------------------------------------
# configure
# ---------------------------------------------------------------------------
def pytest_configure(config):
    config.addinivalue_line(
        "markers", "kpi(**budgets, flight=None): KPI budgets such as "
        "flight_time_s='>= 24 min', checked against the flights of this test (pytest-flockai)")
    config.addinivalue_line(
        "markers", "flockai(drone=, pilot=, world=, tasks=, probes=, seed=, until=, wind=, "
        "name=): quick settings for the pytest-flockai fixtures")
    session = FlockSession(config)   # raises UsageError before anything flies
    config.stash[_SESSION] = session
    config.pluginmanager.register(session, "flockai-session")


def pytest_unconfigure(config):
    session = config.stash.get(_SESSION, None)
    if session is not None:
        config.pluginmanager.unregister(session)
        del config.stash[_SESSION]


# ---------------------------------------------------------------------------
# collection: parse the markers
# ---------------------------------------------------------------------------
def _marker_error(item, marker: str, msg: str) -> str:
    return f"pytest-flockai: bad @pytest.mark.{marker} on {item.nodeid}: {msg}"


def _parse_markers(item, st: TestState) -> None:
    seen: dict = {}
    try:
        for mark in item.iter_markers("kpi"):    # closest first: it wins
            kwargs = dict(mark.kwargs)
            flight = kwargs.pop("flight", None)
            if flight is not None and not isinstance(flight, str):
                raise ConfigError(f"flight = {flight!r} is not allowed; expected the name of a "
                                  f"flight (a str) or None for every flight")
            specs: dict = {}
            for arg in mark.args:
                if not isinstance(arg, dict):
                    raise ConfigError(f"positional argument {arg!r} is not allowed; write budgets "
                                      f"as kpi_name='<= 1.5 s' or a dict {{'probe.metric': '<= 3'}}")
                specs.update(arg)
            specs.update(kwargs)
            if not specs:
                raise ConfigError("no budget given; write e.g. "
                                  "@pytest.mark.kpi(flight_time_s='>= 24 min')")
            for kpi, text in specs.items():
                b = _budgets.parse(kpi, text)
                seen.setdefault((flight, kpi), b)
    except ConfigError as exc:
        st.error = _marker_error(item, "kpi", str(exc))
        return
    st.budgets = [(f, b) for (f, _), b in seen.items()]
    for mark in item.iter_markers("flockai"):
        if mark.args:
            st.error = _marker_error(item, "flockai", f"positional arguments {mark.args!r} are "
                                     f"not allowed; use keywords: {', '.join(FLOCKAI_MARKER_KEYS)}")
            return
        for key in mark.kwargs:
            if key not in FLOCKAI_MARKER_KEYS:
                st.error = _marker_error(item, "flockai", f"unknown setting {key!r}"
                                         f"{close_matches(key, FLOCKAI_MARKER_KEYS)}; allowed: "
                                         f"{', '.join(FLOCKAI_MARKER_KEYS)}")
                return
    try:
        st.max_regression = _regression_setting(_closest(item, "max_regression"))
    except ConfigError as exc:
        st.error = _marker_error(item, "flockai", str(exc))


def _limit_text(session, st) -> str:
    m = st.max_regression
    if isinstance(m, dict):
        extra = ", ".join(f"{k} {v:g}%" for k, v in m.items())
        return f"{session.max_regression:g}%, {extra}"
    return f"{(session.max_regression if m is None else m):g}%"


def _closest(item, key):
    for mark in item.iter_markers("flockai"):
        if key in mark.kwargs:
            return mark.kwargs[key]
    return None


def _regression_setting(value):
    """``max_regression``: None, a percent for every KPI, or ``{kpi: percent}``."""
    def pct(field, v):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0:
            raise ConfigError(f"{field} = {v!r} is not allowed; expected a percentage >= 0 "
                              f"(e.g. 2.5 for 2.5 %)")
        return float(v)
    if value is None:
        return None
    if isinstance(value, dict):
        out = {}
        for kpi, v in value.items():
            if _kpis.get(kpi) is None and "." not in str(kpi):
                raise ConfigError(f"max_regression: unknown KPI {kpi!r}"
                                  f"{close_matches(str(kpi), _kpis.names())}")
            out[kpi] = pct(f"max_regression[{kpi!r}]", v)
        return out
    return pct("max_regression", value)


def pytest_collection_modifyitems(session, config, items):
    for item in items:
        _state(item)


# ---------------------------------------------------------------------------
# running a test
# ---------------------------------------------------------------------------
@pytest.hookimpl(wrapper=True)
def pytest_runtest_protocol(item, nextitem):
    st = _state(item)
    with recording(lambda result, mission: st.record(mission, result)):
        return (yield)


@pytest.hookimpl(tryfirst=True)
def pytest_runtest_setup(item):
    st = _state(item)
    if st.error:
        pytest.fail(st.error, pytrace=False)


def _adopt_fixture_flights(item, st: TestState) -> None:
    """FlightResults the test receives from fixtures but did not fly itself (a
    module- or session-scoped flight fixture) count as its flights, named after
    the fixture."""
    mine = {id(f.result) for f in st.flights}
    for argname, value in (getattr(item, "funcargs", None) or {}).items():
        if isinstance(value, FlightResult) and id(value) not in mine:
            st.record(None, value, name=argname)
            mine.add(id(value))


@pytest.hookimpl(wrapper=True)
def pytest_runtest_call(item):
    st = _state(item)
    _adopt_fixture_flights(item, st)
    try:
        result = yield
    except BaseException:
        try:
            _check(item, st)       # for the report only: the body's error wins
        except Exception:
            pass
        raise
    message = _check(item, st)
    if message:
        pytest.fail(message, pytrace=False)
    return result


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item, call):
    st = item.stash.get(_STATE, None)
    if st is not None:
        _sync_properties(item, st)
    report = yield
    if st is not None and (st.flights or st.budgets or st.error):
        report.flockai = st.payload()
    return report


def _sync_properties(item, st: TestState) -> None:
    """``flockai.<kpi>`` (or ``flockai.<flight>.<kpi>``) user properties for JUnit."""
    props = []
    prefix_flight = len(st.flights) > 1
    for f in st.flights:
        for k, v in f.kpis.items():
            name = f"flockai.{f.name}.{k}" if prefix_flight else f"flockai.{k}"
            props.append((name, _prop_value(v)))
    if props == st._props:
        return
    old = {id(p) for p in st._props}
    item.user_properties[:] = [p for p in item.user_properties if id(p) not in old] + props
    st._props = props


def _prop_value(v) -> str:
    try:
        v = float(v)
    except (TypeError, ValueError):
        return str(v)
    return repr(v) if math.isfinite(v) else str(v)


def _check(item, st: TestState) -> str | None:
    """Evaluate budgets and the baseline; return the failure message or None."""
    st.verdicts, st.regressions, st.problems = [], [], []
    if st.budgets:
        if not st.flights:
            st.problems.append(
                f"pytest-flockai: {item.nodeid} has @pytest.mark.kpi budgets "
                f"({', '.join(sorted({b.kpi for _, b in st.budgets}))}) but flew no mission; use "
                f"the `flight` fixture or call Mission.run() in the test")
        else:
            names = [f.name for f in st.flights]
            for fname, b in st.budgets:
                targets = st.flights if fname is None else [f for f in st.flights if f.name == fname]
                if not targets:
                    st.problems.append(f"pytest-flockai: @pytest.mark.kpi(flight={fname!r}) on "
                                       f"{item.nodeid}: no flight named {fname!r}"
                                       f"{close_matches(fname, names)}; this test flew: "
                                       f"{', '.join(names)}")
                    continue
                if "." in b.kpi and _kpis.get(b.kpi) is not None:
                    try:   # a custom KPI registered since collection: check its unit now
                        b = _budgets.parse(b.kpi, b.text)
                    except ConfigError as exc:
                        st.problems.append(f"pytest-flockai: {exc}")
                        continue
                for f in targets:
                    if b.kpi not in f.kpis:
                        st.problems.append(
                            f"pytest-flockai: budget {b.kpi} {b.text!r}: flight {f.name!r} did "
                            f"not produce KPI {b.kpi!r}{close_matches(b.kpi, f.kpis)}; it "
                            f"produced: {', '.join(f.kpis)}")
                        continue
                    actual = f.kpis[b.kpi]
                    passed, margin = b.evaluate(actual)
                    st.verdicts.append({
                        "flight": f.name, "kpi": b.kpi, "budget": b.text, "op": b.op,
                        "limit": b.limit, "actual": float(actual), "margin": margin,
                        "verdict": "pass" if passed else "fail",
                        "actual_text": b.format(actual),
                        "margin_text": b.format(margin) if margin == margin else "n/a"})
    session = item.config.stash[_SESSION]
    if session.baseline is not None and st.flights:
        base = session.baseline.get(item.nodeid)
        if base:
            limit = session.max_regression
            per_kpi = None
            if isinstance(st.max_regression, dict):
                per_kpi = st.max_regression
            elif st.max_regression is not None:
                limit = st.max_regression
            st.regressions = _report.regressions({f.name: f.kpis for f in st.flights}, base,
                                                 limit, per_kpi=per_kpi)
    parts = list(st.problems)
    broken = [v for v in st.verdicts if v["verdict"] != "pass"]
    if broken:
        parts.append(f"pytest-flockai: {len(broken)} of {len(st.verdicts)} KPI budget(s) broken "
                     f"in {item.nodeid}:\n" + _budget_table(st.verdicts))
    if st.regressions:
        rows = [[r["flight"], r["kpi"], _report.format_kpi(r["kpi"], r["baseline"]),
                 _report.format_kpi(r["kpi"], r["actual"]), f"{r['change_pct']:+.2f}%",
                 r["better"]] for r in st.regressions]
        parts.append(f"pytest-flockai: {len(st.regressions)} KPI regression(s) against baseline "
                     f"{session.baseline_path} (max {_limit_text(session, st)}) in "
                     f"{item.nodeid}:\n"
                     + _report.table(["flight", "KPI", "baseline", "actual", "change",
                                      "better"], rows))
    return "\n".join(parts) or None


def _budget_table(verdicts: list, indent: str = "  ") -> str:
    rows = [[v["flight"], v["kpi"], v["budget"], v.get("actual_text", str(v["actual"])),
             v.get("margin_text", str(v["margin"])),
             "ok" if v["verdict"] == "pass" else "BROKEN"] for v in verdicts]
    return _report.table(["flight", "KPI", "budget", "actual", "margin", "verdict"], rows,
                         indent=indent)


# ---------------------------------------------------------------------------
# fixtures
# ---------------------------------------------------------------------------
def _setting(request, key, default=None):
    """The value for one of the provisioning fixtures: an indirect parametrization
    of that fixture (``@pytest.mark.parametrize("drone", [...], indirect=True)``)
    first, then the closest ``flockai`` marker, then the default."""
    if getattr(request, "fixturename", None) == key and hasattr(request, "param"):
        return request.param
    for mark in request.node.iter_markers("flockai"):   # closest first
        if key in mark.kwargs:
            return mark.kwargs[key]
    return default


@pytest.fixture
def drone(request):
    """A fresh Drone: ``@pytest.mark.flockai(drone=...)`` (a blueprint name, a
    path or a Drone), else ``fa.drone("dji-mavic-2-pro")``."""
    value = _setting(request, "drone", DEFAULT_DRONE)
    if isinstance(value, (str, os.PathLike)):
        return _make_drone(value)
    return value


@pytest.fixture
def world(request):
    """The world to fly in: ``@pytest.mark.flockai(world=...)``, else None (empty)."""
    return _setting(request, "world", None)


@pytest.fixture
def pilot(request):
    """The flight plan: ``@pytest.mark.flockai(pilot=...)``, else
    ``fa.pilots.Hover(altitude=10.0, duration=30.0)``."""
    value = _setting(request, "pilot", None)
    if value is None:
        value = _Hover(altitude=10.0, duration=30.0)
    return value


@pytest.fixture
def tasks(request):
    """ML tasks flown with the mission: ``@pytest.mark.flockai(tasks=...)``, else ()."""
    return tuple(_setting(request, "tasks", ()) or ())


@pytest.fixture
def probes(request):
    """Monitoring probes: ``@pytest.mark.flockai(probes=...)``, else None."""
    return _setting(request, "probes", None)


@pytest.fixture
def mission(request, drone, pilot, world, tasks, probes):
    """The Mission assembled from the fixtures and the ``flockai`` marker (not flown).

    ``pytest_flockai_adjust_mission(mission, item)`` hooks run on it last."""
    m = Mission(drone, pilot, world=world, tasks=tasks, probes=probes,
                wind=_setting(request, "wind", None), seed=_setting(request, "seed", 0),
                until=_setting(request, "until", "landed"), name=_setting(request, "name", None))
    request.config.hook.pytest_flockai_adjust_mission(mission=m, item=request.node)
    return m


@pytest.fixture
def flight(mission):
    """The mission flown: a ``FlightResult`` (recorded for the kpi marker and reports)."""
    return mission.run()
