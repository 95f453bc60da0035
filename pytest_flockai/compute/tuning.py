"""Choosing the latency model's efficiencies on the TUNING half of the published table.

The procedure (``tune``), run by ``benchmarks/latency_tune.py``:

1. Only rows whose source is in the tuning half are read (``Row.half == "tuning"``); the
   held-out rows are never seen by the fit.
2. Parameters, few and shared across computers (a computer enters only through its
   datasheet: peaks, clock, bandwidth):

   - per target (cpu, gpu, npu): depthwise and matrix-product efficiency relative to dense
     convolution, two memory efficiencies (fractions of the sustained bandwidth: one for
     activations, read and written through the caches, one for weights, streamed once from
     DRAM), the dispatch cost per
     node and the per-inference overhead (both at 1 GHz, scaled by the unit's clock), and,
     for the CPU, the parallel efficiency of its threads (n threads compute as
     ``1 + (n - 1) * parallel`` of one: ``runtimes.thread_share``; prior 1, bounds 0.2-1);
   - per runtime/target/precision with tuning rows: one scale of the compute efficiency;
   - per runtime/target with tuning rows: one factor on the dispatch cost (how much a
     runtime fuses and how cheaply it launches: TensorRT against eager PyTorch).
   - one shared Winograd speed-up of dense 3x3 stride-1 convolutions for the runtimes in
     ``predict.WINOGRAD`` (prior 2.25, bounds 1-4).

   Nothing is per network, per computer or per row. A runtime/target/precision without
   tuning rows takes the median scale of the same runtime and target at other precisions,
   else its target's median; a runtime/target without rows, a dispatch factor of 1.
3. Fit: robust least squares (``scipy.optimize.least_squares``, soft-L1 loss with a 0.3
   scale) of ln(predicted / published) over the tuning rows, in log-parameters, with a
   weak pull (weight ``PRIOR_WEIGHT``) toward the untuned priors (``predict.PRIOR_TARGET``)
   so that a parameter the rows cannot see stays at its prior; bounds keep efficiencies
   at or below 1.
4. Written: the parameters, the tuning statistics and, evaluated after the fit and never
   fed back, the held-out half's ranges per computer/runtime (the prediction's ``band``).
5. The rule for deployments without tuning rows (``predict.FALLBACK``) is chosen on the
   tuning half too (``fallback_cv``): each tuned runtime/target/precision is left out of the
   fit in turn and its rows predicted as an untuned group would be, under each candidate
   rule; the rule with the smallest median |ln(predicted/published)| over those rows wins.
6. A change to the model's structure is judged on the tuning half too, by leaving each
   tuning source out in turn (``loso``, ``benchmarks/latency_tune.py --loso``): the median
   over sources of their median |ln(predicted/published)|.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import least_squares

from . import runtimes as _rt
from .devices import DEVICES
from .predict import (
    PRIOR_TARGET,
    PRIOR_WINOGRAD,
    WINOGRAD,
    dispatched,
    efficiencies,
    param_stream,
    params_for,
    roofline,
    stream_gbs,
    winograd_3x3,
)
from .published import BOARD, _stats, band_of, board_of, predict_row

PRIOR_WEIGHT = 0.1
TARGET_PARAMS = ("dwconv", "matmul", "mem", "mem_weights", "dispatch_s", "overhead_s",
                 "parallel")
#: the fit's bounds (efficiencies are fractions of a peak or of the sustained bandwidth; the
#: depthwise and matrix-product figures are relative to dense convolution). Weights are read
#: once per inference, in order, as one sequential stream per layer: at least half of the
#: board's sustained (STREAM, itself a sequential read and write) bandwidth, where the fit
#: was free to put them at a third of it on the GPUs while the activations, read and written
#: through the caches, came out at 0.88 (leave-one-source-out on the tuning half with the
#: floor: 0.257 -> 0.253 over sources, pooled median 0.229 -> 0.215)
BOUNDS = {"dwconv": (0.01, 4.0), "matmul": (0.01, 4.0), "mem": (0.02, 1.0),
          "mem_weights": (0.5, 1.0), "dispatch_s": (1e-7, 2e-3), "overhead_s": (1e-6, 0.2),
          "parallel": (0.2, 1.0)}
_KIND = {"conv": 0, "dwconv": 1, "matmul": 2, "elementwise": 3, "pool": 4, "data": 5}


class _Compiled:
    """One row as arrays, for fast evaluation inside the fit."""

    def __init__(self, row):
        dev = row.device
        dep = row.deployment
        unit = dev.unit(dep.target)
        nodes = dispatched(row.cost.nodes, dep.runtime)
        self.target, self.group = dep.target, dep.key
        self.rt = f"{dep.runtime}/{dep.target}"
        self.peak = _rt.peak_macs(dep, unit)
        self.dep, self.unit = dep, unit
        self.bw = stream_gbs(dev) * 1e9
        self.clock = unit.clock_ghz if unit.clock_ghz > 0 else 1.0
        self.kind = np.array([_KIND[n.kind] for n in nodes], dtype=int)
        self.macs = np.array([float(n.macs) for n in nodes])
        size = _rt.compute_precision(dep, unit)[1]
        self.wbytes = np.array([float(n.weight_elems) for n in nodes]) * size
        self.abytes = np.array([float(n.in_elems + n.out_elems) for n in nodes]) * size
        # parameters streamed from the host at every inference (an accelerator whose own
        # memory cannot hold them all: ``runtimes.param_stream``)
        self.link = unit.link_gbs * 1e9
        cache, held, streamed = unit.cache_mb * 2 ** 20, 0.0, []
        for w in self.wbytes:
            s, held = param_stream(float(w), held, cache) if cache > 0 else (0.0, held)
            streamed.append(s)
        self.sbytes = np.array(streamed)
        self.wino = np.array([winograd_3x3(n) for n in nodes], dtype=bool)
        self.uses_wino = self.rt in WINOGRAD and bool(self.wino.any())
        self.n = len(nodes)
        self.published = row.latency_s

    def seconds(self, tgt: dict, scale: float, dispatch: float = 1.0,
                wino: float = 1.0) -> float:
        eff = np.array([tgt["conv"] * scale, tgt["dwconv"] * scale, tgt["matmul"] * scale,
                        tgt["elementwise"], tgt["pool"], tgt["data"]])
        eff = np.minimum(eff, 1.0)
        tc = self.macs / (self.peak * _rt.thread_share(self.dep, self.unit, tgt.get("parallel", 1.0))
                          * eff[self.kind])
        if self.uses_wino:
            tc = np.where(self.wino, tc / wino, tc)
        tm = (self.abytes / (self.bw * tgt["mem"]) + self.wbytes / (self.bw * tgt["mem_weights"])
              if self.bw > 0 else 0.0 * self.abytes)
        if self.link > 0:
            tm = tm + self.sbytes / (self.link * tgt["mem_weights"])
        return float(np.sum(np.maximum(tc, tm)) + (self.n * tgt["dispatch_s"] * dispatch
                                                   + tgt["overhead_s"]) / self.clock)


def _unpack(theta, targets, groups, rts):
    out_t, out_g, out_d, i = {}, {}, {}, 0
    for t in targets:
        p = dict(PRIOR_TARGET[t])
        conv = p["conv"]
        for name in TARGET_PARAMS:
            v = math.exp(theta[i])
            p[name] = v * conv if name in ("dwconv", "matmul") else v
            i += 1
        out_t[t] = p
    for g in groups:
        out_g[g] = math.exp(theta[i])
        i += 1
    for r in rts:
        out_d[r] = math.exp(theta[i])
        i += 1
    return out_t, out_g, out_d, math.exp(theta[i])


def _prior(targets, groups, rts):
    th, lo, hi = [], [], []
    for t in targets:
        p = PRIOR_TARGET[t]
        for name in TARGET_PARAMS:
            rel = p["conv"] if name in ("dwconv", "matmul") else 1.0
            th.append(math.log(p[name] / rel))
            lo.append(math.log(BOUNDS[name][0]))
            hi.append(math.log(BOUNDS[name][1]))
    for _ in groups:
        th.append(0.0)
        lo.append(math.log(0.01))
        hi.append(math.log(4.0))
    for _ in rts:
        th.append(0.0)
        lo.append(math.log(0.05))
        hi.append(math.log(20.0))
    th.append(math.log(PRIOR_WINOGRAD))         # the Winograd speed-up, shared by all
    lo.append(0.0)
    hi.append(math.log(4.0))
    return np.array(th), np.array(lo), np.array(hi)


def tune(rows) -> dict:
    """The efficiency table fitted on the tuning rows of ``rows`` (see the module docstring)."""
    tuning = [r for r in rows if r.half == "tuning"]
    comp = [_Compiled(r) for r in tuning]
    targets = sorted({c.target for c in comp})
    groups = sorted({c.group for c in comp})
    rts = sorted({c.rt for c in comp})
    th0, lo, hi = _prior(targets, groups, rts)
    th0 = np.clip(th0, lo + 1e-9, hi - 1e-9)

    def resid(theta):
        tg, gs, ds, w = _unpack(theta, targets, groups, rts)
        r = [math.log(c.seconds(tg[c.target], gs[c.group], ds[c.rt], w) / c.published)
             for c in comp]
        return np.concatenate([r, PRIOR_WEIGHT * (theta - th0)])

    fit = least_squares(resid, th0, bounds=(lo, hi), loss="soft_l1", f_scale=0.3,
                        x_scale=1.0, max_nfev=4000)
    tg, gs, ds, w = _unpack(fit.x, targets, groups, rts)
    return {"winograd": {"factor": float(w), "runtimes": sorted(WINOGRAD),
                         "rows": sum(c.uses_wino for c in comp)},
            "targets": {t: {k: float(v) for k, v in p.items()} for t, p in tg.items()},
            "dispatch": {r: {"factor": float(v), "rows": sum(c.rt == r for c in comp)}
                         for r, v in ds.items()},
            "groups": {g: {"scale": float(v), "rows": sum(c.group == g for c in comp)}
                       for g, v in gs.items()},
            "fit": {"rows": len(comp), "cost": float(fit.cost), "nfev": int(fit.nfev),
                    "success": bool(fit.success), "prior_weight": PRIOR_WEIGHT}}


#: the candidate rules for untuned deployments (``predict.FALLBACK``)
FALLBACK_RULES = tuple({"scale": s, "dispatch": d} for s in ("runtime", "target")
                       for d in ("prior", "target"))


def fallback_cv(rows) -> dict:
    """Leave-one-group-out on the tuning half: for each tuned runtime/target/precision,
    refit without its rows and predict them under each rule of ``FALLBACK_RULES``.
    Returns {"rule": the best rule, "candidates": [{rule, median_abs_ln, rows}, ...]}."""
    tuning = [r for r in rows if r.half == "tuning"]
    groups = sorted({r.group for r in tuning})
    errs: list[list[float]] = [[] for _ in FALLBACK_RULES]
    for g in groups:
        table = tune([r for r in tuning if r.group != g])
        for r in (r for r in tuning if r.group == g):
            dev = r.device
            dep = r.deployment
            for i, rule in enumerate(FALLBACK_RULES):
                t = {**table, "fallback": {"rule": rule}}
                secs = roofline(r.cost, dev, dep, params_for(t, dep))[0]
                errs[i].append(abs(math.log(secs / r.latency_s)))
    med = [float(np.median(e)) for e in errs]
    best = int(np.argmin(med))
    cands = [{"rule": rule, "median_abs_ln": m, "rows": len(e)}
             for rule, m, e in zip(FALLBACK_RULES, med, errs)]
    return {"rule": FALLBACK_RULES[best], "candidates": cands, "groups_left_out": len(groups)}


def loso(rows, fallback: dict | None = None) -> dict:
    """Leave-one-source-out on the tuning half: for each tuning source, fit on the other
    tuning sources and predict its rows. How a change to the model is judged without the
    held-out half: a new source is what a user's own deployment looks like, so the figure
    that counts is the median over sources of each source's median |ln(predicted /
    published)| (every source weighs the same), with the pooled median and mean beside it.

    Returns {"per_source": {source: {"n", "median_abs_ln"}}, "median_of_sources",
    "pooled_median", "pooled_mean"}. ``fallback``: the rule for untuned deployments (the
    stored one when None)."""
    tuning = [r for r in rows if r.half == "tuning"]
    rule = efficiencies().get("fallback", {}) if fallback is None else fallback
    per, pooled = {}, []
    for src in sorted({r.source_id for r in tuning}):
        table = {**tune([r for r in tuning if r.source_id != src]), "fallback": rule}
        e = [abs(math.log(predict_row(r, table) / r.latency_s))
             for r in tuning if r.source_id == src]
        per[src] = {"n": len(e), "median_abs_ln": float(np.median(e))}
        pooled += e
    return {"per_source": per,
            "median_of_sources": float(np.median([v["median_abs_ln"] for v in per.values()])),
            "pooled_median": float(np.median(pooled)), "pooled_mean": float(np.mean(pooled))}


def loco(rows, fallback: dict | None = None, boards=None) -> dict:
    """Leave-one-computer-out: for each board (its power modes together, ``BOARD``), fit on
    the tuning rows of the other boards and predict every row of that board, tuning and
    held out: how the model does on a computer it was never tuned on, as a computer a user
    describes by its own datasheet (``compute.computer``) is.

    Returns {"per_board": {board: {half: {"n", "median_abs_ln", "within_2x"}}}, "all":
    {half: the same over every board's rows}, "ratios": [(board, half, target,
    predicted/published), ...]}; ``boards``: only these (None: all)."""
    tuning = [r for r in rows if r.half == "tuning"]
    rule = efficiencies().get("fallback", {}) if fallback is None else fallback
    per: dict = {}
    out = []
    every = sorted({board_of(r.computer) for r in rows})
    for board in every if boards is None else [b for b in every if b in boards]:
        table = {**tune([r for r in tuning if board_of(r.computer) != board]), "fallback": rule}
        for half in ("tuning", "heldout"):
            mine = [r for r in rows if board_of(r.computer) == board and r.half == half]
            rr = [predict_row(r, table) / r.latency_s for r in mine]
            out += [(board, half, r.target, v) for r, v in zip(mine, rr)]
            if rr:
                per.setdefault(board, {})[half] = _abs_ln_stats(rr)
    pooled = {h: _abs_ln_stats([v for _, hh, _, v in out if hh == h])
              for h in ("tuning", "heldout") if any(hh == h for _, hh, _, _ in out)}
    return {"per_board": per, "all": pooled, "ratios": out}


def _abs_ln_stats(ratios) -> dict:
    """``published``'s statistics of ratios predicted/published, the ones ``loco`` keeps."""
    s = _stats(np.asarray(ratios, dtype=float))
    return {k: s[k] for k in ("n", "median_abs_ln", "within_2x")}


def loco_bands(cv: dict) -> dict:
    """{"untuned/*/<target>": {"min", "max", "lo", "hi", "n", "sources"}}: the range of published /
    predicted over the held-out rows of ``loco``'s boards, each predicted by a fit that never
    saw it (``sources``: the boards)."""
    out: dict = {}
    for board, half, target, ratio in cv["ratios"]:
        if half != "heldout":
            continue
        b = out.setdefault(f"untuned/*/{target}", {"v": [], "boards": set()})
        b["v"].append(1.0 / ratio)
        b["boards"].add(board)
    return {k: {**band_of(b["v"]), "sources": len(b["boards"])} for k, b in out.items()}


def tuned_computers(rows) -> list[str]:
    """The profiles whose board has tuning rows (its power modes included: ``BOARD``)."""
    boards = {board_of(r.computer) for r in rows if r.half == "tuning"}
    return sorted(n for n in DEVICES if board_of(n) in boards)


__all__ = ["BOARD", "BOUNDS", "FALLBACK_RULES", "PRIOR_WEIGHT", "TARGET_PARAMS", "fallback_cv",
           "loco", "loco_bands", "loso", "tune", "tuned_computers"]
