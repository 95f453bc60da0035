"""``flockai compare BASE.json NEW.json [--threshold 5%] [--abs-tol KPI=VALUE]``.

Both files may be JSON reports (``--flockai-json``) or baselines
(``--flockai-save``). Each KPI of each flight of each test present in both is
compared in its better direction (the registry in ``kpis.py``). A change no
larger than the KPI's absolute tolerance (``kpis.abs_tolerance``, overridable)
or than a millionth of the value is noise: "same". A KPI worse than the base by
more than the threshold (percent of the base value) and its absolute tolerance
is a regression, and the command exits 1; otherwise 0.

The story comes first (``render``): one screen of summary, the scenario
changes of the tests that changed (``scenario.py``: drone, computer, model,
link, world, conditions, seed), then the regressions grouped by cause and
sorted by size, one row per KPI family and test (``det.recall`` and
``recall``, or every drone's ``flight_time_s``, folded across the flights);
the per-KPI rows only with ``--all``.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

from .. import kpis as _kpis
from ..errors import close_matches
from ..kpis import NOISE_REL as NOISE_REL  # the one regression rule, the gate's too
from ..kpis import classify as classify
from ..kpis import family as family
from ..kpis import tolerance as tolerance
from . import files as _report
from . import scenario as _scenario


@dataclass(frozen=True)
class Delta:
    test: str
    flight: str
    kpi: str
    base: float | None
    new: float | None
    better: str | None          # "higher", "lower" or None
    status: str                 # "regression", "worse", "better", "same", "changed", "n/a"

    @property
    def change_pct(self) -> float | None:
        if self.base is None or self.new is None or not math.isfinite(self.base) \
                or not math.isfinite(self.new):
            return None
        if self.base == 0:
            return 0.0 if self.new == 0 else math.copysign(math.inf, self.new)
        return (self.new - self.base) / abs(self.base) * 100.0

    def to_dict(self) -> dict:
        return {"test": self.test, "flight": self.flight, "kpi": self.kpi, "base": self.base,
                "new": self.new, "change_pct": self.change_pct, "better": self.better,
                "status": self.status, "family": family(self.kpi)}


@dataclass(frozen=True)
class Group:
    """One row of the story: a KPI family of one test, across its flights."""

    test: str
    family: str
    status: str                 # the worst status of its deltas
    worst: Delta                # the delta with the largest change in the worse direction
    count: int                  # deltas folded into this row
    flights: tuple              # the flights they come from
    cause: str                  # the test's scenario changes ("" when none is known)

    @property
    def size(self) -> float:
        c = self.worst.change_pct
        return abs(c) if c is not None else 0.0


@dataclass
class Comparison:
    deltas: list
    only_base: list             # tests in the base only
    only_new: list              # tests in the new file only
    threshold_pct: float
    causes: dict = field(default_factory=dict)   # test -> [scenario change lines]

    @property
    def regressions(self) -> list:
        return [d for d in self.deltas if d.status == "regression"]

    def groups(self, statuses=("regression",)) -> list[Group]:
        """Rows for the deltas of ``statuses``: one per (test, KPI family), biggest first."""
        return group(self.deltas, self.causes, statuses)


def parse_threshold(text) -> float:
    """``"5%"``, ``"5"`` or ``5`` -> 5.0; raises ValueError for anything else."""
    s = str(text).strip().rstrip("%").strip()
    v = float(s)
    if not (v >= 0 and math.isfinite(v)):
        raise ValueError(f"threshold = {text!r} is not allowed; expected a percentage >= 0, "
                         f"e.g. 5%")
    return v


def parse_abs_tol(items) -> dict:
    """``["energy_total_j=5", "cpu_utilization=0.01"]`` -> ``{kpi: float}`` (SI units);
    raises ValueError naming the item for anything else."""
    out = {}
    for item in items or ():
        for part in str(item).split(","):
            kpi, sep, value = part.partition("=")
            try:
                v = float(value)
            except ValueError:
                v = math.nan
            if not sep or not kpi.strip() or not (v >= 0 and math.isfinite(v)):
                raise ValueError(f"abs tolerance {part!r} is not allowed; expected KPI=VALUE "
                                 f"with VALUE >= 0 in the KPI's SI unit, e.g. energy_total_j=5")
            kpi = kpi.strip()
            if _kpis.get(kpi) is None and "." not in kpi:     # as the abs_tol marker setting
                raise ValueError(f"abs tolerance {part!r}: unknown KPI {kpi!r}"
                                 f"{close_matches(kpi, _kpis.names())}; allowed: a name from "
                                 f"pytest_flockai.kpis.names() or a custom '<probe>.<metric>'")
            out[kpi] = v
    return out


def _num(v):
    if v is None or isinstance(v, bool):
        return None
    try:
        return float(v)
    except (TypeError, ValueError):
        return None


def compare(base: dict, new: dict, threshold_pct: float = 5.0, *, abs_tol: dict | None = None,
            base_scenarios: dict | None = None, new_scenarios: dict | None = None) -> Comparison:
    """Compare ``{test: {flight: {kpi: value}}}`` mappings; the scenarios
    (``scenario.of_report``) give each test's cause."""
    deltas = []
    for test in sorted(set(base) & set(new)):
        for flight in sorted(set(base[test]) & set(new[test])):
            bk, nk = base[test][flight], new[test][flight]
            for kpi in sorted(set(bk) | set(nk)):
                b, n = _num(bk.get(kpi)), _num(nk.get(kpi))
                better, status = classify(kpi, b, n, threshold_pct, abs_tol)
                deltas.append(Delta(test, flight, kpi, b, n, better, status))
    causes = {}
    if base_scenarios and new_scenarios:
        for test in sorted(set(base) & set(new)):
            lines = _scenario.changes_of(base_scenarios, new_scenarios, test)
            if lines:
                causes[test] = lines
    return Comparison(deltas, sorted(set(base) - set(new)), sorted(set(new) - set(base)),
                      threshold_pct, causes)


_RANK = {"regression": 0, "worse": 1, "better": 2, "changed": 3, "same": 4, "n/a": 5}


def _badness(d: Delta) -> float:
    c = d.change_pct
    if c is None:
        return -math.inf
    return -c if d.better == "higher" else c


def group(deltas, causes: dict, statuses=("regression",)) -> list[Group]:
    """One row per (test, KPI family) among the deltas of ``statuses``: grouped by
    cause (the tests sharing a scenario change together), biggest change first."""
    by: dict = {}
    for d in deltas:
        if d.status in statuses:
            by.setdefault((d.test, family(d.kpi)), []).append(d)
    rows = []
    for (test, fam), ds in by.items():
        ds.sort(key=lambda d: (_RANK[d.status], -_badness(d)))
        rows.append(Group(test, fam, ds[0].status, ds[0], len(ds),
                          tuple(dict.fromkeys(d.flight for d in ds)),
                          "; ".join(causes.get(test, ()))))
    cause_size: dict = {}
    for r in rows:
        cause_size[r.cause] = max(cause_size.get(r.cause, 0.0), r.size)
    rows.sort(key=lambda r: (r.cause == "", -cause_size[r.cause], r.cause, _RANK[r.status],
                             -r.size, r.test, r.family))
    return rows


def load_scenarios(path) -> dict:
    """The scenario summaries a report or baseline file keeps (``{}`` when none)."""
    try:
        return _scenario.of_report(json.loads(Path(path).read_text(encoding="utf-8")))
    except (OSError, ValueError):
        return {}


def compare_files(base_path, new_path, threshold_pct: float = 5.0, *,
                  abs_tol: dict | None = None) -> Comparison:
    """Raises ``report.ReportError`` for a file that is not a report or baseline."""
    return compare(_report.load_baseline(base_path), _report.load_baseline(new_path),
                   threshold_pct, abs_tol=abs_tol, base_scenarios=load_scenarios(base_path),
                   new_scenarios=load_scenarios(new_path))


def format_change(d: Delta) -> str:
    c = d.change_pct
    if c is None:
        return "n/a"
    return f"{c:+.2f}%" if math.isfinite(c) else ("+inf%" if c > 0 else "-inf%")


def counts(cmp: Comparison) -> dict:
    """How many KPIs (with a better direction) are in each status."""
    out = {s: 0 for s in _RANK}
    for d in cmp.deltas:
        if d.better is not None or d.status == "n/a":
            out[d.status] += 1
    return out


def headline(cmp: Comparison) -> str:
    """The one line a reader needs: regressions (rows and tests), then the rest."""
    c = counts(cmp)
    regs = cmp.groups()
    tests = len({g.test for g in regs})
    first = (f"{len(regs)} regression(s) in {tests} test(s) beyond {cmp.threshold_pct:g}%"
             if regs else f"no regression beyond {cmp.threshold_pct:g}%")
    return (f"{first}; {c['worse']} KPI(s) worse within the threshold, {c['better']} better, "
            f"{c['same']} unchanged (within each KPI's absolute tolerance)")


def _group_rows(groups) -> list[list[str]]:
    rows = []
    for g in groups:
        d = g.worst
        flights = d.flight if len(g.flights) == 1 else f"{len(g.flights)} flights"
        rows.append([_short(g.test), g.family + (f" (x{g.count})" if g.count > 1 else ""),
                     flights, _report.format_kpi(d.kpi, d.base), _report.format_kpi(d.kpi, d.new),
                     format_change(d), d.better or ""])
    return rows


def render(cmp: Comparison, *, show_all: bool = False, limit: int = 20) -> str:
    """The summary, the scenario changes, the regressions (one row per KPI family and
    test, biggest first, at most ``limit`` unless ``show_all``), then with
    ``show_all`` every changed KPI."""
    out = [headline(cmp)]
    causes: dict = {}
    for test, lines in cmp.causes.items():
        causes.setdefault("; ".join(lines), []).append(test)
    if causes:
        out += ["", "scenario changes:"]
        for cause, tests in sorted(causes.items(), key=lambda kv: -len(kv[1])):
            out.append(f"  {cause}  ({len(tests)} test(s): {', '.join(_short(t) for t in tests[:3])}"
                       f"{', ...' if len(tests) > 3 else ''})")
    regs = cmp.groups()
    if regs:
        out += ["", "regressions, biggest first (one row per KPI family and test):"]
        shown = regs if show_all else regs[:limit]
        last = None
        for g in shown:
            if g.cause != last:
                out.append(f"  cause: {g.cause or 'no scenario change known'}")
                last = g.cause
                block = [x for x in shown if x.cause == g.cause]
                out.append(_report.table(["test", "KPI family", "flights", "base", "new",
                                          "change", "better"], _group_rows(block), indent="    "))
        if len(shown) < len(regs):
            out.append(f"  ... {len(regs) - len(shown)} more (--all shows every row)")
    for t in cmp.only_base:
        out.append(f"only in the base: {t}")
    for t in cmp.only_new:
        out.append(f"only in the new run: {t}")
    if show_all:
        rows = [[_short(d.test), d.flight, d.kpi, _report.format_kpi(d.kpi, d.base),
                 _report.format_kpi(d.kpi, d.new), format_change(d), d.better or "", d.status]
                for d in cmp.deltas if d.status not in ("same", "n/a")]
        out += ["", "every changed KPI:"]
        out.append(_report.table(["test", "flight", "KPI", "base", "new", "change", "better",
                                  "status"], rows, indent="") if rows else "none")
    return "\n".join(out)


def _short(nodeid: str) -> str:
    return nodeid if len(nodeid) <= 60 else "..." + nodeid[-57:]
