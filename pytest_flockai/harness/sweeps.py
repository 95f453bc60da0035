"""``@pytest.mark.flockai_sweep(**axes, samples=, method=, seed=, workers=, executor=,
batch_size=, progress=)``: the
test flies a sweep of the ``mission`` fixture (``fa.sweep``) through the
``flockai_sweep`` fixture (requested for every marked test; ask for it to get
the DataFrame). The test's ``@pytest.mark.kpi`` budgets are checked on every
variant; the test fails listing the variants that broke one (axis values and
KPI). The JSON report gets the sweep's rows under ``"sweep"``; with
``--flockai-artifacts DIR`` the envelope is written there as
``<test>/sweep.csv`` and ``sweep.png`` (a KPI over the first two axes), and the
picture goes to the HTML reports.

``--flockai-sweep-executor ADDRESS`` (ini ``flockai_sweep_executor``) sends the
variants of every marked sweep to the Dask scheduler at ``ADDRESS``: one
``distributed.Client`` per pytest process (the ``flockai_sweep_executor``
fixture, session-scoped), connected at the first sweep and closed at the end.
A sweep interrupted by Ctrl-C fails its test with the rows finished so far (the
others ``interrupted``), which go to the reports, and stops the run after it.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from .. import budgets as _budgets
from ..errors import ConfigError
from ..reports import files as _report
from .ci_reports import PICTURE_PROPERTY
from .options import option
from .recorder import STATE

MARKER = "flockai_sweep"


def configure(config) -> None:
    """A UsageError for a ``--flockai-sweep-executor`` that is no scheduler address."""
    address, from_ini = option(config, "sweep-executor")
    if address is None or getattr(config.option, "help", False):
        return
    what = "flockai_sweep_executor (ini)" if from_ini else "--flockai-sweep-executor"
    from ..sweeps import executors  # lazy: only a run that asks for a cluster loads the core
    try:
        executors.check_address(address, what)
    except ConfigError as exc:
        raise pytest.UsageError(f"pytest-flockai: {exc}") from None


@pytest.fixture(scope="session")
def flockai_sweep_executor(pytestconfig):
    """The Dask client of ``--flockai-sweep-executor`` (None without the option)."""
    address, _ = option(pytestconfig, "sweep-executor")
    if address is None:
        yield None
        return
    from ..sweeps import executors  # lazy: only a run that asks for a cluster loads the core
    try:
        client = executors.connect(address)
    except ConfigError as exc:
        pytest.fail(f"pytest-flockai: --flockai-sweep-executor: {exc}", pytrace=False)
    try:
        yield client
    finally:
        client.close()


def marked(item) -> bool:
    return item.get_closest_marker(MARKER) is not None


def request_fixture(item) -> None:
    """A marked test flies its sweep even when it does not ask for the fixture."""
    names = getattr(item, "fixturenames", None)
    if marked(item) and names is not None and MARKER not in names:
        names.append(MARKER)


@pytest.fixture
def flockai_sweep(request, mission, flockai_sweep_executor):
    """The sweep of ``@pytest.mark.flockai_sweep`` flown from the ``mission`` fixture:
    a DataFrame, one row per variant, with the test's kpi budgets as ``ok_*``/``ok``."""
    mark = request.node.get_closest_marker(MARKER)
    if mark is None:
        pytest.fail(f"pytest-flockai: the {MARKER} fixture needs @pytest.mark.{MARKER}(...)",
                    pytrace=False)
    if mark.args:
        pytest.fail(f"pytest-flockai: bad @pytest.mark.{MARKER}: positional arguments "
                    f"{mark.args!r} are not allowed; write axes as keywords "
                    f"(payload_kg=[0.0, 0.2])", pytrace=False)
    st = request.node.stash[STATE]
    budgets = {fb.budget.kpi: fb.budget.text for fb in st.markers.budgets if fb.flight is None}
    kwargs = dict(mark.kwargs)
    if flockai_sweep_executor is not None:
        kwargs.setdefault("executor", flockai_sweep_executor)
    from ..sweeps import runner  # lazy: the core loads on first use
    try:
        df = runner.sweep(mission, budgets=budgets or None, **kwargs)
    except ConfigError as exc:
        pytest.fail(f"pytest-flockai: bad @pytest.mark.{MARKER} on {request.node.nodeid}: {exc}",
                    pytrace=False)
    st.sweep = df
    if df.attrs.get("interrupted"):     # the test fails with the rows so far; the run stops
        request.session.shouldstop = (f"pytest-flockai: the sweep of {request.node.nodeid} was "
                                      f"interrupted; its finished rows are in the reports")
    return df


def check(item, st) -> str | None:
    """The kpi budgets against every variant of the sweep, into ``st.verdicts``;
    the failure message lists the variants that broke one, and their errors."""
    df = st.sweep
    axes = df.attrs.get("axes", [])
    named = sorted({x.flight for x in st.markers.budgets if x.flight is not None})
    if named:
        st.problems.append(f"pytest-flockai: @pytest.mark.kpi(flight=...) on {item.nodeid}: a "
                           f"sweep checks its budgets on every variant; flight = {named[0]!r} is "
                           f"not allowed with @pytest.mark.{MARKER}")
    budgets = [x.budget for x in st.markers.budgets if x.flight is None]
    from ..sweeps import envelope_files as envelope  # lazy: a sweep flew, so it is loaded already
    st.verdicts, broken, errors = [], [], []
    for _, row in df.iterrows():
        name = envelope.label(row, axes)
        mine = [b.verdict(_value(row, b.kpi), flight=name) for b in budgets]
        st.verdicts += mine
        broken += [v for v in mine if not v.passed]
        if isinstance(row.get("error"), str):
            errors.append(f"  {name}: {row['error']}")
    if not broken and not errors:
        return None
    bad = df[~df["ok"].astype(bool)] if "ok" in df else df[df["error"].notna()]
    text = (f"pytest-flockai: {len(bad)} of {len(df)} sweep variant(s) broke a budget or "
            f"failed in {item.nodeid}:\n")
    if broken:
        text += _budgets.table(broken)
    if errors:
        text += "\n  failed variants:\n" + "\n".join(errors)
    return text


def _value(row, kpi):
    v = row.get(kpi)
    try:
        v = float(v)
    except (TypeError, ValueError):
        return None
    return None if v != v else v


def write_envelope(item, st, artifacts) -> None:
    """The envelope as CSV and picture under the artifacts folder; the picture also
    goes to the HTML reports. A KPI of the first budget (else flight_time_s) over
    the first two axes."""
    if artifacts is None or st.sweep is None:
        return
    df = st.sweep
    axes = df.attrs.get("axes", [])
    kpi = next((x.budget.kpi for x in st.markers.budgets), "flight_time_s")
    x, y = (axes + axes)[:2] if axes else ("", "")
    from ..sweeps import envelope_files as envelope  # lazy: a sweep flew, so it is loaded already
    try:
        folder = Path(artifacts) / _report.safe_name(item.nodeid)   # the flights' folder
        folder.mkdir(parents=True, exist_ok=True)
        written = envelope.save(df, folder / "sweep", x, y, kpi)
    except OSError as exc:
        st.warnings.append(f"pytest-flockai: sweep envelope of {item.nodeid} not written to "
                           f"{artifacts}: {exc.strerror or exc}")
        return
    st.sweep_files = [str(p) for p in written]
    for p in written:
        if p.suffix == ".png":
            item.user_properties.append((PICTURE_PROPERTY, (f"sweep envelope: {kpi}", str(p))))

