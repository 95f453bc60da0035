"""The KPI table at the end of a run: headline KPIs per flight (every KPI and
the budget table with ``-v``; one line with ``-q``)."""

from __future__ import annotations

from .. import budgets as _budgets
from .. import kpis as _kpis
from ..reports import files as _report

HEADLINE_KPIS = ("flight_time_s", "energy_total_j", "mean_power_w", "battery_remaining",
                 "inference_latency_p50_s")


def summary(tr, config, entries, files) -> None:
    entries = [e for e in entries if e["flights"] or e["budgets"] or e["error"]
               or e["outcome"] in ("interrupted", "crashed") or e.get("baseline_missing")]
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
        if e.get("baseline_missing"):
            status += ", not in baseline: " + ", ".join(e["baseline_missing"])
        tr.write_line(f"{e['nodeid']} ({status})")
        if e["outcome"] in ("interrupted", "crashed") and e.get("message"):
            tr.write_line(f"  {e['message']}")
        if e.get("hypothesis"):
            tr.write_line("  " + _hypothesis_line(e["hypothesis"]))
        for f in e["flights"]:
            kp = f["kpis"]
            if verbose:
                rows = [[k, _report.format_kpi(k, v), _better(k)] for k, v in kp.items()]
                tr.write_line(f"  flight {f['name']!r}: {f.get('end_reason')}, "
                              f"drone {_drone_name(f)}")
                tr.write_line(_report.table(["KPI", "value", "better"], rows, indent="    "))
            else:
                names = [k for k in HEADLINE_KPIS if k in kp]
                for b in budgets:
                    if b["kpi"] in kp and b["kpi"] not in names:
                        names.append(b["kpi"])
                cells = "  ".join(f"{k}={_report.format_kpi(k, kp[k])}" for k in names)
                tr.write_line(f"  {f['name']}{_cached(f)}: {cells}")
        if verbose and budgets:
            tr.write_line(_budgets.table([_budgets.Verdict.from_dict(b) for b in budgets],
                                         indent="    "))
    for line in files:
        tr.write_line(f"flockai: {line}")


def _hypothesis_line(h: dict) -> str:
    ranges = "  ".join(f"{k} {_report.format_kpi(k, lo)}..{_report.format_kpi(k, hi)}"
                       for k, (lo, hi) in h.get("kpi_ranges", {}).items() if k in HEADLINE_KPIS)
    kept = "the failing example in full" if h.get("kept") else "no example kept in full"
    return (f"hypothesis: {h['examples']} example(s), {h['flights']} flight(s) ({kept}); "
            f"{ranges}").rstrip("; ")


def _cached(flight: dict) -> str:
    return " (cached)" if (flight.get("cache") or {}).get("status") == "hit" else ""


def _better(kpi):
    info = _kpis.get(kpi)
    return (info.better or "") if info is not None else ""


def _drone_name(flight: dict):
    d = (flight.get("scenario") or {}).get("drone")
    if isinstance(d, dict):
        return d.get("name", "?")
    return str(d)
