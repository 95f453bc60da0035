"""Inference latency and energy predicted from the network, the runtime and the precision.

``predict_latency(model, device, *, runtime=None, precision=None, target=None, threads=None)``
walks the network's nodes (``compute.graph.analyze``: MACs, weight and activation
elements and class per node, normalisation and activations fused into their
convolution as runtimes fuse them) and times each node on the deployment's unit as a
roofline: the slower of

- compute: ``macs / (peak[precision] * eff[target][kind] * scale[runtime/target/precision])``
  (``kind``: conv, dwconv, matmul, elementwise, pool, data), and
- memory: ``activation bytes / (stream_gbs * mem[target]) + weight bytes / (stream_gbs *
  mem_weights[target])``, activation bytes = (inputs + outputs) and weight bytes = weights,
  each x the precision's element size (two efficiencies: weights are streamed once from
  DRAM, activations are written and read back through the caches and the runtime's layout
  changes), ``stream_gbs`` the board's measured STREAM bandwidth where published, else
  ``STREAM_OF_PEAK`` of the DRAM peak,

with dense 3x3 stride-1 convolutions' compute divided by a tuned Winograd speed-up on the
runtimes of ``WINOGRAD``, and a gated activation (SiLU, hard-swish) its own element-wise
pass where the runtime does not fuse it (``GATE_FUSED``, ``dispatched``);
plus a dispatch cost per unfused node (``dispatch_s[target]`` at 1 GHz times a factor per
runtime/target, scaled by the unit's clock), plus a per-inference overhead. The efficiencies (``eff``, ``mem``,
``scale``, ``dispatch_s``, ``overhead_s``) are read from ``data/latency_efficiencies.json``,
written by ``benchmarks/latency_tune.py`` from the TUNING half of the published
measurements only (the procedure is in that script); the same file records, per
(computer, runtime), the ratios predicted/published on the held-out half, which give
``LatencyPrediction.band``.

Energy per inference: ``seconds * (active_w - idle_w) * share`` (the computer's busy power
above idle at its board input, measured where published; ``share``: on a CPU the
deployment's threads over the cores, else 1: ``runtimes.power_share``).

A model known only by its MAC count (``predict_latency(5.3e8, ...)``) falls back to the
computer's MAC-count rule ``overhead_s + macs / macs_per_s`` with a ``LatencyFallbackWarning``.
A ``MeasuredDevice`` (``compute.profile``) answers with its measured samples instead.
"""

from __future__ import annotations

import json
import math
import os
import warnings
from dataclasses import dataclass, replace
from functools import lru_cache
from pathlib import Path

import numpy as np

from ..errors import ConfigError
from . import runtimes as _rt
from ._fusion import ACT_UNFUSED, GATE_FUSED, dispatched
from .devices import Device
from .devices import device as _device
from .graph import analyze
from .measured import is_measured
from .ort_graph import as_run
from .runtimes import param_stream

EFFICIENCIES = Path(__file__).with_name("data") / "latency_efficiencies.json"
KINDS = ("conv", "dwconv", "matmul", "elementwise", "pool", "data")
#: untuned priors (used where the tuning file has no figure): dense convolution runs at a
#: fraction of peak, depthwise far below it (low arithmetic intensity); memory (``mem`` for
#: activations, ``mem_weights`` for weights, the same prior) as
#: a fraction of the sustained STREAM bandwidth (``stream_gbs``), set so that the prior
#: keeps its earlier value as a fraction of the DRAM peak (0.4 / 0.73, 0.5 / 0.73,
#: 0.3 / 0.73); a few microseconds per kernel dispatch at 1 GHz.
PRIOR_TARGET = {
    "cpu": {"conv": 0.5, "dwconv": 0.15, "matmul": 0.5, "elementwise": 0.25, "pool": 0.25,
            "data": 0.25, "mem": 0.55, "mem_weights": 0.55, "dispatch_s": 20e-6, "overhead_s": 1e-3,
            "parallel": 1.0},
    "gpu": {"conv": 0.4, "dwconv": 0.05, "matmul": 0.4, "elementwise": 0.1, "pool": 0.1,
            "data": 0.1, "mem": 0.68, "mem_weights": 0.68, "dispatch_s": 10e-6, "overhead_s": 1e-3,
            "parallel": 1.0},
    "npu": {"conv": 0.5, "dwconv": 0.2, "matmul": 0.3, "elementwise": 0.1, "pool": 0.1,
            "data": 0.1, "mem": 0.41, "mem_weights": 0.41, "dispatch_s": 5e-6, "overhead_s": 2e-3,
            "parallel": 1.0},
}


#: runtimes whose dense 3x3 stride-1 convolutions run as Winograd F(m x m, 3 x 3) kernels,
#: which need fewer multiplications than the direct MAC count: ncnn on Arm CPUs and on Vulkan
#: GPUs (its ``convolution_3x3_winograd`` kernels, chosen for 3x3 s1 with >= 8 input channels
#: by default: ``Option::use_winograd_convolution``) and TensorRT (cuDNN's / TensorRT's
#: Winograd tactics for 3x3 s1).
WINOGRAD = frozenset(("ncnn/cpu",))
#: untuned prior of the effective speed-up of a Winograd convolution over the direct one:
#: F(2x2, 3x3) cuts the multiplications 2.25x (Lavin and Gray, "Fast Algorithms for
#: Convolutional Neural Networks", CVPR 2016, section 4); larger tiles cut more (F(4x4, 3x3):
#: 4x) but pay for transforms. The tuned figure lies in [1, 4].
PRIOR_WINOGRAD = 2.25


#: sustained (STREAM) bandwidth as a fraction of the DRAM wire rate where a board has no
#: published STREAM figure: Texas Instruments measure 67-79 % on (LP)DDR4 Arm SoCs (app notes
#: SPRACV1B, AM64x "STREAM" table: 67-79 %; SPRAD45A, AM62x: 74-78 %); 0.73, their middle.
STREAM_OF_PEAK = 0.73


def stream_gbs(dev: Device) -> float:
    """The board's sustained memory bandwidth, GB/s: its measured STREAM figure where one is
    published (``memory_bandwidth_stream_gbs`` in computers.toml), else ``STREAM_OF_PEAK`` of
    the DRAM peak."""
    s = float(getattr(dev, "stream_gbs", 0.0) or 0.0)
    return s if s > 0 else STREAM_OF_PEAK * dev.bandwidth_gbs


def winograd_3x3(n) -> bool:
    """Whether a node is a dense 3x3 stride-1 convolution with >= 8 input channels, read from
    its counts alone: MACs = out x Cin x k^2 and, at stride 1, the input's spatial size is the
    output's (MACs / weights), so k^2 = (MACs / out) / (in / (MACs / weights))."""
    if n.kind != "conv" or not (n.macs and n.weight_elems and n.in_elems and n.out_elems):
        return False
    spatial = n.macs / n.weight_elems
    cin = n.in_elems / spatial
    return cin >= 8 and 7.0 <= (n.macs / n.out_elems) / cin <= 11.0


#: held-out rows a (computer, runtime) needs for its own band (else its target's band)
MIN_BAND_ROWS = 4
#: a band of this many held-out rows or more is the central ``BAND_COVER`` of their ratios
#: (the 5th to the 95th percentile): one doubtful row among a hundred would otherwise set it
#: (the CPU's band was x0.29..x8.1, set by four OpenVINO rows of one guide); with fewer
#: rows it is their whole range
BAND_QUANTILE_ROWS = 20
BAND_COVER = 0.90
#: publishers those rows must come from: rows of one publisher (two revisions of one maker's
#: guide) measure that publisher's agreement with itself, not the spread a user will see
MIN_BAND_SOURCES = 2


class LatencyFallbackWarning(UserWarning):
    """The latency came from the MAC-count rule, not from the network's layers."""


@dataclass(frozen=True)
class LatencyPrediction:
    """One inference: ``seconds``, ``band`` (low, high seconds: the held-out half's range of
    published/predicted for this computer and runtime; when that pair has fewer than
    ``MIN_BAND_ROWS`` held-out rows or they come from fewer than ``MIN_BAND_SOURCES``
    publishers, for every runtime of this computer on the same unit (by the same rule);
    failing that, for every computer's rows on that unit; for a computer no published row
    was fitted on (a team's own datasheet, ``compute.computer``), the leave-one-computer-out
    range on that unit), ``energy_j`` above idle, and
    ``per_node``: ((node, kind, seconds, bound), ...)."""

    seconds: float
    band: tuple[float, float]
    energy_j: float
    device: str
    runtime: str | None
    target: str | None
    precision: str | None
    threads: int | None
    method: str                      # "roofline", "macs" (fallback) or "measured"
    macs: float
    per_node: tuple = ()
    #: roofline only: whether published rows of this runtime, target and precision were
    #: fitted (False: its scale is borrowed, ``FALLBACK``); None for the other methods
    tuned: bool | None = None

    @property
    def milliseconds(self) -> float:
        return 1e3 * self.seconds

    def to_dict(self) -> dict:
        return {"seconds": self.seconds, "band": list(self.band), "energy_j": self.energy_j,
                "device": self.device, "runtime": self.runtime, "target": self.target,
                "precision": self.precision, "threads": self.threads, "method": self.method,
                "macs": self.macs, "tuned": self.tuned}


@lru_cache(maxsize=4)
def _load_table(path: str, mtime: float) -> dict:
    with open(path, encoding="utf-8") as fh:
        return json.load(fh)


def efficiencies(path=None) -> dict:
    """The tuned efficiency table (``{}`` before any tuning)."""
    p = Path(path) if path is not None else EFFICIENCIES
    if not p.is_file():
        return {}
    return _load_table(str(p), p.stat().st_mtime)


#: how a deployment without tuning rows gets its figures (the tuning file's ``fallback.rule``
#: overrides this default; ``benchmarks/latency_tune.py`` chooses it by leaving each tuned
#: group out of the fit in turn, on the tuning half only: ``tuning.fallback_cv``):
#: ``scale``: "runtime" (the median scale of the same runtime and target at other
#: precisions, else the target's median) or "target" (the target's median scale);
#: ``dispatch``: "prior" (factor 1) or "target" (the median factor of the target's runtimes).
FALLBACK = {"scale": "runtime", "dispatch": "prior"}


def params_for(table: dict, dep: _rt.Deployment) -> dict:
    """The efficiencies for one deployment: the target's figures (tuned, else the prior)
    with the group's ``scale`` (tuned for this runtime/target/precision, else by the
    ``FALLBACK`` rule, else 1), and the dispatch cost times the runtime/target's tuned
    ``dispatch`` factor (else by the ``FALLBACK`` rule)."""
    tgt = {**PRIOR_TARGET[dep.target], **table.get("targets", {}).get(dep.target, {})}
    rule = {**FALLBACK, **table.get("fallback", {}).get("rule", {})}
    groups = table.get("groups", {})
    g = groups.get(dep.key)
    if g is None:          # untuned: see FALLBACK
        rt = [v["scale"] for k, v in groups.items()
              if k.split("/")[:2] == [dep.runtime, dep.target]]
        tg = [v["scale"] for k, v in groups.items() if k.split("/")[1] == dep.target]
        same = (rt or tg) if rule["scale"] == "runtime" else tg
        scale = float(np.median(same)) if same else 1.0
    else:
        scale = float(g["scale"])
    disp = table.get("dispatch", {})
    d = disp.get(f"{dep.runtime}/{dep.target}")
    if d is not None:
        tgt["dispatch_s"] = tgt["dispatch_s"] * float(d["factor"])
    elif rule["dispatch"] == "target":
        same = [v["factor"] for k, v in disp.items() if k.split("/")[1] == dep.target]
        tgt["dispatch_s"] = tgt["dispatch_s"] * (float(np.median(same)) if same else 1.0)
    wino = 1.0
    if f"{dep.runtime}/{dep.target}" in WINOGRAD:
        wino = float(table.get("winograd", {}).get("factor", PRIOR_WINOGRAD))
    return {**tgt, "scale": scale, "winograd": wino, "tuned": g is not None}


def roofline(cost, dev: Device, dep: _rt.Deployment, prm: dict) -> tuple[float, tuple]:
    """(seconds, per-node timings) of a network cost on a deployment with efficiencies."""
    unit = dev.unit(dep.target)
    peak = _rt.peak_macs(dep, unit) * _rt.thread_share(dep, unit, prm.get("parallel", 1.0))
    bw = stream_gbs(dev) * 1e9 * prm["mem"]
    bw_w = stream_gbs(dev) * 1e9 * prm["mem_weights"]
    nbytes = _rt.compute_precision(dep, unit)[1]
    clock = unit.clock_ghz if unit.clock_ghz > 0 else 1.0
    dispatch = prm["dispatch_s"] / clock
    total, per = prm["overhead_s"] / clock, []
    # an accelerator with its own parameter memory (the Edge TPU): the parameters that do not
    # fit stream over the host link at every inference (``param_stream``)
    cache = unit.cache_mb * 2 ** 20
    link = unit.link_gbs * 1e9 * prm["mem_weights"]
    held = 0.0
    # a layer the runtime computes in float inside an int8 graph (``ort_graph``): fp32's
    # peak, element size and scale (``prm["scale_float"]``, set by predict_latency)
    as_float = None
    if "scale_float" in prm:
        fdep = replace(dep, precision="fp32")
        as_float = (_rt.peak_macs(fdep, unit) * _rt.thread_share(fdep, unit, prm.get("parallel", 1.0)),
                    _rt.compute_precision(fdep, unit)[1], prm["scale_float"])
    for n in dispatched(cost.nodes, dep.runtime):
        pk, nb, sc = as_float if n.in_float and as_float else (peak, nbytes, prm["scale"])
        eff = min(1.0, prm[n.kind] * (sc if n.kind in ("conv", "dwconv", "matmul") else 1.0))
        tc = n.macs / (pk * eff) if n.macs else 0.0
        if prm.get("winograd", 1.0) != 1.0 and winograd_3x3(n):
            tc /= prm["winograd"]
        tm = ((n.in_elems + n.out_elems) * nb / bw + n.weight_elems * nb / bw_w
              if bw > 0 else 0.0)
        if cache > 0 and link > 0 and n.weight_elems:
            streamed, held = param_stream(n.weight_elems * nb, held, cache)
            tm += streamed / link
        t = max(tc, tm) + dispatch
        total += t
        per.append((n.name, n.kind, t, "compute" if tc >= tm else "memory"))
    return total, tuple(per)


def above_idle_w(dev: Device, dep: _rt.Deployment | None) -> float:
    """W above idle one inference on ``dep`` draws: the busy power above idle times the
    deployment's share of it (``runtimes.power_share``: on a CPU its threads over the cores)."""
    unit = dev.unit(dep.target) if dep is not None else None
    return (dev.active_w - dev.idle_w) * _rt.power_share(dep, unit)


def _band(table: dict, dev: Device, dep: _rt.Deployment, seconds: float) -> tuple[float, float]:
    bands = table.get("bands", {})
    tuned = table.get("tuned_computers")
    if tuned is not None and dev.name not in tuned and bands.get(f"untuned/*/{dep.target}"):
        b = bands[f"untuned/*/{dep.target}"]
    else:
        b = _own_band(bands, dev, dep)
    if not b:
        return (seconds / 2.0, seconds * 2.0)       # untuned: the 2x bound
    return (seconds * float(b.get("lo", b["min"])), seconds * float(b.get("hi", b["max"])))


def _own_band(bands: dict, dev: Device, dep: _rt.Deployment) -> dict | None:
    """The band of this computer and runtime, else of this computer on the unit, else of
    every computer on the unit (``LatencyPrediction``)."""
    b = None
    for key in (f"{dev.name}/{dep.runtime}", f"{dev.name}/*/{dep.target}"):
        b = bands.get(key)
        if (b and b.get("n", 0) >= MIN_BAND_ROWS
                and b.get("sources", MIN_BAND_SOURCES) >= MIN_BAND_SOURCES):
            break
    else:           # too few rows on this computer: the target's held-out range
        b = bands.get(f"*/{dep.target}")
    return b


def _cost(model, input_shape):
    """A network cost (nodes) from a NetworkCost, an OnnxModel, a path, bytes or a proto."""
    if hasattr(model, "nodes"):
        return model
    if hasattr(model, "_proto") and hasattr(model, "input_name"):        # an OnnxModel
        proto = model._proto if model._proto is not None else model._load_proto(model.path)
        return analyze(proto, input_shape)
    if isinstance(model, (str, os.PathLike)):
        return _cached_analyze(os.fspath(model), os.stat(model).st_mtime, input_shape)
    return analyze(model, input_shape)


@lru_cache(maxsize=32)
def _cached_analyze(path: str, mtime: float, input_shape):
    return analyze(path, input_shape)


def _resolve_dev(dev):
    if isinstance(dev, str):
        return _device(dev)
    return dev


def predict_latency(model, device, *, runtime=None, precision=None, target=None, threads=None,
                    input_shape=None, efficiencies_path=None) -> LatencyPrediction:
    """Seconds (and band, energy) of one batch-1 inference of ``model`` on ``device``.

    ``model``: an ONNX path, bytes or ModelProto, an ``OnnxModel``, a ``NetworkCost`` or a
    MAC count (the fallback rule, with a warning). ``device``: a profile name, a ``Device``
    or a ``MeasuredDevice``. ``runtime``/``precision``/``target``/``threads``: the
    deployment (defaults: the computer's first listed runtime and its default precision;
    int8 for a quantized graph, QDQ or QOperator, where the runtime runs int8).
    ``input_shape``: the full input shape for a graph with dynamic dims."""
    dev = _resolve_dev(device)
    if is_measured(dev) or getattr(dev, "measured", None) is not None:   # a measured profile
        return _measured(model, dev)
    if not isinstance(dev, Device):
        raise ConfigError(f"device = {device!r} is not a device; expected a profile name "
                          f"(fa.devices()), a Device or a MeasuredDevice (fa.compute.profile)")
    if isinstance(model, (int, float)) and not isinstance(model, bool):
        return _from_macs(float(model), dev, runtime, precision, target, threads)
    _rt.check_names(runtime, precision, target, threads, where="predict_latency")
    cost = _cost(model, tuple(input_shape) if input_shape is not None else None)
    dep = _rt.resolve(dev, runtime, precision, target, threads, where="predict_latency",
                      quantized=getattr(cost, "meta", {}).get("int8"),
                      half=bool(getattr(cost, "meta", {}).get("fp16")))
    table = efficiencies(efficiencies_path)
    prm = params_for(table, dep)
    if dep.runtime == "onnxruntime" and dep.precision == "int8" and "_graph" in cost.meta:
        cost = as_run(cost)             # the layers ONNX Runtime leaves in float (ort_graph)
        prm["scale_float"] = params_for(table, replace(dep, precision="fp32"))["scale"]
    secs, per = roofline(cost, dev, dep, prm)
    macs = float(sum(n.macs for n in cost.nodes))
    return LatencyPrediction(secs, _band(table, dev, dep, secs), secs * above_idle_w(dev, dep),
                             dev.name, dep.runtime, dep.target, dep.precision, dep.threads,
                             "roofline", macs, per, bool(prm["tuned"]))


def _from_macs(macs, dev, runtime, precision, target, threads) -> LatencyPrediction:
    if macs < 0 or not math.isfinite(macs):
        raise ConfigError(f"model = {macs!r} is not allowed; a MAC count must be a finite "
                          f"number >= 0")
    _rt.check_names(runtime, precision, target, threads, where="predict_latency")
    warnings.warn(f"predict_latency: a bare MAC count ({macs:.3g}) gives the computer's "
                  f"MAC-count rule (overhead_s + macs / macs_per_s), not the layer model: pass "
                  f"the ONNX model for a latency that depends on its layers and the runtime",
                  LatencyFallbackWarning, stacklevel=3)
    s = mac_rule_seconds(macs, dev)
    return LatencyPrediction(s, (s / 2.0, s * 2.0), s * (dev.active_w - dev.idle_w), dev.name,
                             runtime, target, precision, threads, "macs", macs)


def mac_rule_seconds(macs: float, dev: Device) -> float:
    """The MAC-count rule: ``overhead_s + macs / macs_per_s``."""
    return dev.overhead_s + float(macs) / dev.macs_per_s


def _measured(model, dev) -> LatencyPrediction:
    if not is_measured(dev):
        dev = dev.measured
    s = np.asarray(dev.latency_samples(model), dtype=np.float64)
    p5, p50, p95 = (float(x) for x in np.percentile(s, (5, 50, 95)))
    busy = getattr(dev, "busy_w", None)
    idle = getattr(dev, "idle_w", None)
    e = p50 * (busy - idle) if busy is not None and idle is not None else math.nan
    return LatencyPrediction(p50, (p5, p95), e, str(getattr(dev, "name", "measured")),
                             getattr(dev, "runtime", None), getattr(dev, "target", None),
                             getattr(dev, "precision", None), getattr(dev, "threads", None),
                             "measured", math.nan)


__all__ = ["ACT_UNFUSED", "BAND_COVER", "BAND_QUANTILE_ROWS", "EFFICIENCIES", "FALLBACK", "KINDS", "MIN_BAND_ROWS", "MIN_BAND_SOURCES", "param_stream", "GATE_FUSED", "PRIOR_WINOGRAD", "dispatched", "STREAM_OF_PEAK", "WINOGRAD",
           "stream_gbs", "winograd_3x3", "LatencyFallbackWarning", "LatencyPrediction",
           "above_idle_w", "efficiencies", "mac_rule_seconds", "params_for", "predict_latency",
           "roofline"]
