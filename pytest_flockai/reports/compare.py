"""``flockai compare BASE.json NEW.json [--threshold 5%]``: KPI deltas across commits.

Both files may be JSON reports (``--flockai-json``) or baselines
(``--flockai-save``). Each KPI of each flight of each test present in both is
compared in its better direction (the registry in ``kpis.py``); a KPI worse
than the base by more than the threshold (percent of the base value) is a
regression, and the command exits 1; otherwise 0 (2 for a file it cannot read).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .. import kpis as _kpis
from .. import report as _report


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
                "status": self.status}


@dataclass
class Comparison:
    deltas: list
    only_base: list             # tests in the base only
    only_new: list              # tests in the new file only
    threshold_pct: float

    @property
    def regressions(self) -> list:
        return [d for d in self.deltas if d.status == "regression"]


def parse_threshold(text) -> float:
    """``"5%"``, ``"5"`` or ``5`` -> 5.0; raises ValueError for anything else."""
    s = str(text).strip().rstrip("%").strip()
    v = float(s)
    if not (v >= 0 and math.isfinite(v)):
        raise ValueError(f"threshold = {text!r} is not allowed; expected a percentage >= 0, "
                         f"e.g. 5%")
    return v


def _num(v):
    if v is None or isinstance(v, bool):
        return None
    try:
        return float(v)
    except (TypeError, ValueError):
        return None


def classify(kpi: str, base, new, threshold_pct: float) -> tuple[str | None, str]:
    """(better direction, status) of one KPI; the tolerance matches the plugin's
    baseline gate (``report.regressions``)."""
    info = _kpis.get(kpi)
    better = info.better if info is not None else None
    if base is None or new is None or not (math.isfinite(base) and math.isfinite(new)):
        return better, "n/a"
    if new == base:
        return better, "same"
    if better is None:
        return better, "changed"
    tol = abs(base) * threshold_pct / 100.0 + 1e-9 * max(1.0, abs(base))
    worse = new < base if better == "higher" else new > base
    if not worse:
        return better, "better"
    beyond = new < base - tol if better == "higher" else new > base + tol
    return better, "regression" if beyond else "worse"


def compare(base: dict, new: dict, threshold_pct: float = 5.0) -> Comparison:
    """Compare ``{test: {flight: {kpi: value}}}`` mappings."""
    deltas = []
    for test in sorted(set(base) & set(new)):
        for flight in sorted(set(base[test]) & set(new[test])):
            bk, nk = base[test][flight], new[test][flight]
            for kpi in sorted(set(bk) | set(nk)):
                b, n = _num(bk.get(kpi)), _num(nk.get(kpi))
                better, status = classify(kpi, b, n, threshold_pct)
                deltas.append(Delta(test, flight, kpi, b, n, better, status))
    return Comparison(deltas, sorted(set(base) - set(new)), sorted(set(new) - set(base)),
                      threshold_pct)


def compare_files(base_path, new_path, threshold_pct: float = 5.0) -> Comparison:
    """Raises ``report.ReportError`` for a file that is not a report or baseline."""
    return compare(_report.load_baseline(base_path), _report.load_baseline(new_path),
                   threshold_pct)


_MARK = {"regression": "REGRESSION", "worse": "worse", "better": "better", "same": "",
         "changed": "changed", "n/a": "n/a"}


def format_change(d: Delta) -> str:
    c = d.change_pct
    if c is None:
        return "n/a"
    return f"{c:+.2f}%" if math.isfinite(c) else ("+inf%" if c > 0 else "-inf%")


def render(cmp: Comparison, *, show_all: bool = False) -> str:
    """The comparison as a text table (KPIs with a better direction that changed,
    or every KPI with ``show_all``), then the regressions and the summary."""
    rows = []
    for d in cmp.deltas:
        if not show_all and (d.better is None or d.status in ("same", "n/a")):
            continue
        rows.append([_short(d.test), d.flight, d.kpi, _report.format_kpi(d.kpi, d.base),
                     _report.format_kpi(d.kpi, d.new), format_change(d),
                     {"higher": "higher", "lower": "lower"}.get(d.better, ""), _MARK[d.status]])
    out = []
    if rows:
        out.append(_report.table(["test", "flight", "KPI", "base", "new", "change", "better",
                                  "status"], rows, indent=""))
    else:
        out.append("no KPI with a better direction changed")
    for t in cmp.only_base:
        out.append(f"only in the base: {t}")
    for t in cmp.only_new:
        out.append(f"only in the new run: {t}")
    n = len(cmp.regressions)
    counted = [d for d in cmp.deltas if d.better is not None and d.status != "n/a"]
    out.append(f"{len(counted)} KPI(s) compared, {sum(d.status == 'better' for d in counted)} "
               f"better, {sum(d.status in ('worse', 'regression') for d in counted)} worse, "
               f"{n} regression(s) beyond {cmp.threshold_pct:g}%")
    return "\n".join(out)


def _short(nodeid: str) -> str:
    return nodeid if len(nodeid) <= 60 else "..." + nodeid[-57:]
