"""Inference latency on a device profile: ``modeled`` and ``measured``.

``modeled`` (the default, deterministic) for a model known only by its MAC count (a
``PythonModel(fn, macs=...)``, a template) is the computer's MAC-count rule::

    latency = device.overhead_s + macs / device.macs_per_s

(an ONNX model's modeled latency comes from its layers instead: ``predict.predict_latency``).

``measured``: the host's wall time of the *real* inference, scaled to the computer's CPU.
The scale comes from a calibration benchmark run once per process: a fixed convolutional
ONNX model (built in memory) is timed with ONNX Runtime on one host core, and the same
network is predicted by the layer model (``predict.predict_latency``) on one core of the
computer's CPU (ONNX Runtime where the computer lists it, else its first CPU runtime, at
fp32). Then::

    latency = overhead_s + wall_s * compute_s(calibration net on the computer) / median_s(host)

with ``overhead_s`` that deployment's per-inference overhead (``HostScale``). So code that
runs as fast on the host as the calibration network gets the layer model's time on the
computer's core, and code that runs slower (memory bound, Python, unusual operators) gets
proportionally more. A computer with no CPU runtime in its datasheet (the Coral board lists
only its Edge TPU, ``ground-gpu`` only its GPU) keeps the MAC-count rule's rate
(``wall_s * host_macs_per_s / device.macs_per_s``). The host's code runs on the host's CPU,
so this is a CPU-to-CPU scale: for a GPU or NPU deployment of an ONNX model use the modeled
latency or a measured profile (``flockai profile-device``). Measured results are not
reproducible by nature (they depend on the host and its load): use them to see what a
model's code costs, not as CI budgets.
"""

from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import onnxruntime as ort
from onnx import TensorProto, helper, numpy_helper

from ..errors import ConfigError
from .devices import Device
from .devices import device as _device
from .measured import as_device, is_measured
from .predict import predict_latency

LATENCY_MODES = ("modeled", "measured")


def resolve_device(dev, field: str = "device") -> Device:
    """A ``Device`` from a profile name or a ``Device``; ConfigError otherwise."""
    if isinstance(dev, Device):
        return dev
    if is_measured(dev):            # a measured profile: its samples, a datasheet's power
        return as_device(dev)
    if isinstance(dev, str):
        try:
            return _device(dev)
        except ConfigError as e:
            raise ConfigError(f"{field} = {dev!r}: {e}") from None
    raise ConfigError(f"{field} = {dev!r} is not a device; expected a profile name "
                      f"(see pytest_flockai.devices()), a Device or a measured profile "
                      f"(fa.compute.profile(path))")


def device_value(value, where: str) -> tuple[str, Device | None]:
    """(the name ``Drone.device`` holds, the profile) of a profile name, "none", a ``Device``
    (``fa.compute.computer``) or a measured profile (``fa.compute.profile``); ConfigError
    naming ``where`` otherwise."""
    if value == "none":
        return value, None
    try:
        dev = resolve_device(value, "device")
    except ConfigError as e:
        raise ConfigError(f"{where}: {e}" + ("" if isinstance(value, str) else "; or \"none\"")
                          ) from None
    return dev.name, dev


def compute_seconds(macs: float, device) -> float:
    """Seconds of pure compute for ``macs`` on ``device`` (no per-call overhead)."""
    return float(macs) / resolve_device(device).macs_per_s


def modeled_latency(macs, device) -> float:
    """Seconds for one inference of ``macs`` multiply-accumulates on ``device``.

    Deterministic: ``overhead_s + macs / macs_per_s``.
    """
    dev = resolve_device(device)
    if macs is None:
        raise ConfigError("macs = None: the modeled latency needs the model's MAC count; "
                          "give the model macs=... or use latency='measured'")
    if isinstance(macs, bool) or not isinstance(macs, (int, float)) or macs < 0 or not math.isfinite(macs):
        raise ConfigError(f"macs = {macs!r} is not allowed; expected a finite number >= 0")
    return dev.overhead_s + compute_seconds(macs, dev)


@dataclass(frozen=True)
class Calibration:
    """The host benchmark behind ``measured`` latency."""

    host_macs_per_s: float   # median effective MAC rate of the host (ONNX Runtime, CPU)
    macs: int                # MACs of the calibration network per run
    runs: int
    median_s: float
    p10_s: float
    p90_s: float

    @property
    def spread(self) -> float:
        """(p90 - p10) / median of the calibration runs: the timing noise of this host."""
        return (self.p90_s - self.p10_s) / self.median_s if self.median_s > 0 else math.nan

    def to_dict(self) -> dict:
        return {"host_macs_per_s": self.host_macs_per_s, "macs": self.macs, "runs": self.runs,
                "median_s": self.median_s, "p10_s": self.p10_s, "p90_s": self.p90_s,
                "spread": self.spread}


_CAL: Calibration | None = None
_CAL_LOCK = threading.Lock()


def _calibration_model_bytes() -> bytes:
    """Three 3x3 convolutions + ReLU on a 1x16x64x64 tensor; fixed seed weights."""

    rng = np.random.default_rng(12345)
    nodes, inits = [], []
    c_in = 16
    name = "x"
    for i, c_out in enumerate((32, 32, 16)):
        w = numpy_helper.from_array((rng.standard_normal((c_out, c_in, 3, 3)) * 0.1)
                                    .astype(np.float32), f"w{i}")
        inits.append(w)
        nodes.append(helper.make_node("Conv", [name, f"w{i}"], [f"c{i}"], pads=[1, 1, 1, 1]))
        nodes.append(helper.make_node("Relu", [f"c{i}"], [f"r{i}"]))
        name, c_in = f"r{i}", c_out
    graph = helper.make_graph(
        nodes, "flockai_calibration",
        [helper.make_tensor_value_info("x", TensorProto.FLOAT, [1, 16, 64, 64])],
        [helper.make_tensor_value_info(name, TensorProto.FLOAT, [1, 16, 64, 64])], inits)
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 13)])
    model.ir_version = 8
    return model.SerializeToString()


def calibrate(*, runs: int = 15, force: bool = False) -> Calibration:
    """Benchmark the host once per process (cached); about 0.1-0.3 s on 2 cores."""
    global _CAL
    with _CAL_LOCK:
        if _CAL is not None and not force:
            return _CAL

        # exact MACs of the calibration net: 64*64 outputs per channel
        macs = 64 * 64 * (32 * 16 * 9 + 32 * 32 * 9 + 16 * 32 * 9)
        opts = ort.SessionOptions()
        opts.intra_op_num_threads = 1      # one core: like one inference thread on the drone
        opts.inter_op_num_threads = 1
        opts.log_severity_level = 3
        sess = ort.InferenceSession(_calibration_model_bytes(), opts,
                                    providers=["CPUExecutionProvider"])
        x = np.random.default_rng(0).standard_normal((1, 16, 64, 64)).astype(np.float32)
        for _ in range(3):
            sess.run(None, {"x": x})
        times = []
        for _ in range(max(3, int(runs))):
            t0 = time.perf_counter()
            sess.run(None, {"x": x})
            times.append(time.perf_counter() - t0)
        med = float(np.median(times))
        _CAL = Calibration(host_macs_per_s=macs / med, macs=macs, runs=len(times), median_s=med,
                           p10_s=float(np.percentile(times, 10)),
                           p90_s=float(np.percentile(times, 90)))
        return _CAL


@dataclass(frozen=True)
class HostScale:
    """How host seconds become a computer's: ``overhead_s + wall_s * factor``.

    ``rule``: what set it (the layer model's deployment, or the MAC-count rule)."""

    factor: float
    overhead_s: float
    rule: str

    def to_dict(self) -> dict:
        return {"factor": self.factor, "overhead_s": self.overhead_s, "rule": self.rule}


def _cpu_deployment(dev: Device) -> str | None:
    """The CPU runtime the host's calibration is compared with: ONNX Runtime where the
    computer lists it (the calibration ran in it), else its first CPU runtime."""
    cpu = [d.split("/")[0] for d in dev.deployments if d.endswith("/cpu")]
    return "onnxruntime" if "onnxruntime" in cpu else (cpu[0] if cpu else None)


@lru_cache(maxsize=64)
def _host_scale(dev: Device, cal: Calibration) -> HostScale:
    runtime = _cpu_deployment(dev)
    if runtime is None or getattr(dev, "measured", None) is not None:
        why = ("a measured profile has no datasheet to predict from" if runtime else
               f"{dev.name!r} lists no CPU runtime")
        return HostScale(cal.host_macs_per_s / dev.macs_per_s, dev.overhead_s,
                         f"MAC-count rule: {why}")
    p = predict_latency(_calibration_model_bytes(), dev, runtime=runtime, target="cpu",
                        precision="fp32", threads=1)
    compute = float(sum(n[2] for n in p.per_node))
    return HostScale(compute / cal.median_s, p.seconds - compute,
                     f"layer model: {runtime}/cpu/fp32, 1 thread")


def host_scale(device, calibration: Calibration | None = None) -> HostScale:
    """The scale from this host's seconds to ``device``'s (see the module docstring)."""
    return _host_scale(resolve_device(device), calibration or calibrate())


def scale_to_device(wall_s: float, device, calibration: Calibration | None = None) -> float:
    """Device seconds for an inference that took ``wall_s`` on this host."""
    sc = host_scale(device, calibration)
    return sc.overhead_s + float(wall_s) * sc.factor


def measured_latency(fn, *args, device, calibration: Calibration | None = None):
    """Run ``fn(*args)`` once, timing it on the host; return (result, device seconds, wall s).

    Exceptions from ``fn`` propagate.
    """
    cal = calibration or calibrate()
    t0 = time.perf_counter()
    out = fn(*args)
    wall = time.perf_counter() - t0
    return out, scale_to_device(wall, device, cal), wall


__all__ = ["LATENCY_MODES", "Calibration", "HostScale", "calibrate", "compute_seconds", "device_value",
           "host_scale", "measured_latency", "modeled_latency", "resolve_device", "scale_to_device"]
