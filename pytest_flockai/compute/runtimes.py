"""Runtimes, targets and precisions: what a deployment is, and what a computer can run.

A deployment is a (runtime, target, precision, threads) on a computer (``Device``):

- runtimes: ``onnxruntime``, ``tflite``, ``ncnn``, ``openvino``, ``opencv-dnn``,
  ``pytorch``, ``tensorrt``, ``edgetpu``;
- targets: ``cpu``, ``gpu``, ``npu`` (the compute unit the runtime runs the network on);
- precisions: ``fp32``, ``fp16``, ``int8``.

``RUNTIME_TARGETS`` says on which units each runtime can run at all (TensorRT: NVIDIA
GPUs only, per NVIDIA's TensorRT support matrix; the Edge TPU runtime: the Edge TPU
only, int8 only, per Coral's "TensorFlow models on the Edge TPU" page: "the Edge TPU
supports only 8-bit" quantized models). A computer's datasheet (``Device.deployments``)
says which of these it has; ``resolve`` checks a request against it and fills the
defaults (the computer's first listed deployment for a runtime; the unit's first
precision), raising a ``ConfigError`` that names the field, the value and what is
allowed, and both the computer and the runtime when the combination is impossible.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from numbers import Integral

from ..errors import ConfigError, close_matches

RUNTIMES = ("onnxruntime", "tflite", "ncnn", "openvino", "opencv-dnn", "pytorch", "tensorrt",
            "edgetpu")
TARGETS = ("cpu", "gpu", "npu")
PRECISIONS = ("fp32", "fp16", "int8")
#: bytes per tensor element at each precision
BYTES = {"fp32": 4, "fp16": 2, "int8": 1}
#: the units each runtime can use at all (the computer narrows this down)
RUNTIME_TARGETS: dict[str, tuple[str, ...]] = {
    "onnxruntime": ("cpu", "gpu"), "tflite": ("cpu", "gpu", "npu"), "ncnn": ("cpu", "gpu"),
    "openvino": ("cpu", "gpu", "npu"), "opencv-dnn": ("cpu", "gpu"), "pytorch": ("cpu", "gpu"),
    "tensorrt": ("gpu",), "edgetpu": ("npu",),
}
#: CPU threads a runtime uses when none are asked for, where that is not every core: TF
#: Lite's Python ``Interpreter`` without ``num_threads`` leaves the thread count to the
#: runtime (-1), and its default XNNPACK delegate then gets no thread pool (TensorFlow
#: Lite's delegate options: ``num_threads > 1 ? num_threads : 0``; XNNPACK delegate README,
#: "XNNPACK engine being single-threaded by default", TensorFlow PR 45061); ONNX Runtime,
#: ncnn, OpenVINO, OpenCV DNN and PyTorch use every core by default.
DEFAULT_THREADS = {"tflite": 1}
#: precisions each runtime can execute (Edge TPU: int8 only)
RUNTIME_PRECISIONS: dict[str, tuple[str, ...]] = {r: PRECISIONS for r in RUNTIMES}
RUNTIME_PRECISIONS["edgetpu"] = ("int8",)


class ModelPrecisionWarning(UserWarning):
    """A model is predicted at another precision than its graph's: the deployment cannot run
    the graph's (``QuantizedModelWarning``, ``HalfModelWarning``), or runs only int8 and the
    graph is float (the Edge TPU)."""


class QuantizedModelWarning(ModelPrecisionWarning):
    """An int8 (quantized) model is predicted at another precision: the deployment cannot
    run int8."""


class HalfModelWarning(ModelPrecisionWarning):
    """An fp16 model is predicted at another precision: the deployment cannot run fp16."""


@dataclass(frozen=True)
class Deployment:
    """A resolved (runtime, target, precision, threads) on one computer."""

    runtime: str
    target: str
    precision: str
    threads: int | None = None

    @property
    def key(self) -> str:
        """``runtime/target/precision``: the key of the tuned efficiencies."""
        return f"{self.runtime}/{self.target}/{self.precision}"

    def to_dict(self) -> dict:
        return {"runtime": self.runtime, "target": self.target, "precision": self.precision,
                "threads": self.threads}


#: runtimes whose fp32 convolutions run as TF32 on tensor cores by default (Ampere and
#: later): TensorRT ("TF32 is enabled by default", TensorRT developer guide, "Reduced
#: Precision"), PyTorch (``torch.backends.cudnn.allow_tf32`` defaults to True, PyTorch
#: notes "TensorFloat-32 (TF32) on Ampere devices"), ONNX Runtime's CUDA provider
#: (``use_tf32`` defaults to 1, CUDA Execution Provider options)
TF32_BY_DEFAULT = frozenset(("tensorrt", "pytorch", "onnxruntime"))


#: CPU runtimes that run an fp32 model in fp16 on a CPU with fp16 arithmetic (Armv8.2-A
#: and later: the Raspberry Pi 5's Cortex-A76, the Orins' Cortex-A78AE), unless told not to:
#: ncnn (its defaults ``use_fp16_arithmetic`` / ``use_fp16_storage`` are true, ncnn
#: ``src/option.cpp``) and OpenVINO's CPU plugin from 2024.0 on ("On platforms that natively
#: support half-precision calculations (bfloat16 or float16), the half-precision type (bf16
#: or f16) is automatically used instead of f32 ... float16 data type enables the
#: armv8.2-a+fp16 extension on ARM64 CPUs": OpenVINO documentation, "CPU Device", section
#: "Floating Point Data Types Specifics"; its ``execution_mode`` hint defaults to
#: PERFORMANCE; the 2023.3 page lists f32 only for Arm).
FP16_ON_ARMV82 = frozenset(("ncnn", "openvino"))


def compute_precision(dep: Deployment, unit) -> tuple[str, float]:
    """(precision the arithmetic runs at, bytes per stored element) of a deployment.

    - ncnn and OpenVINO on a CPU with fp16 arithmetic (Armv8.2: Cortex-A76, A78AE) compute
      and store in fp16 when asked for fp32 (``FP16_ON_ARMV82``);
    - ONNX Runtime's CPU provider runs an fp16 model in fp32: it implements few operators in
      fp16 and casts to fp32 around the others (ONNX Runtime docs, "Float16 and mixed
      precision models"; the CPU provider's kernels are fp32);
    - eager PyTorch's fp16 convolutions on a GPU without tensor cores (the Jetson Nano's
      Maxwell) run at the fp32 rate with fp16 storage: its cuDNN convolution descriptor sets
      the math type to float for half data (PyTorch ``aten/src/ATen/cudnn/Descriptors.h``,
      ``ConvolutionDescriptor::set``: ``if (dataType == CUDNN_DATA_HALF) mathType =
      CUDNN_DATA_FLOAT``), and only tensor-op math brings half-precision rates;
    - fp32 on a GPU with tensor cores runs TF32 (half the fp16 tensor rate) with the
      runtimes of ``TF32_BY_DEFAULT``; element size stays 4 bytes.
    """
    p = dep.precision
    if dep.runtime == "onnxruntime" and dep.target == "cpu" and p == "fp16":
        return "fp32", float(BYTES["fp32"])
    if (dep.runtime in FP16_ON_ARMV82 and dep.target == "cpu" and p == "fp32"
            and "fp16" in unit.precisions):
        return "fp16", float(BYTES["fp16"])
    if (dep.runtime == "pytorch" and dep.target == "gpu" and p == "fp16"
            and getattr(unit, "tensor_cores", 0) == 0):
        return "fp32", float(BYTES["fp16"])
    if (p == "fp32" and dep.target == "gpu" and dep.runtime in TF32_BY_DEFAULT
            and getattr(unit, "tensor_cores", 0) > 0 and "fp16" in unit.precisions):
        return "tf32", float(BYTES["fp32"])
    return p, float(BYTES[p])


def power_share(dep: Deployment | None, unit) -> float:
    """The share of the computer's busy power above idle (``busy_w - idle_w``) that one
    inference on this deployment draws: on a CPU, its threads over the cores (a core's
    dynamic power is drawn while it computes, and ``busy_w`` is the board with every core
    busy: the Raspberry Pis' figures are all-core CPU loads; on the Jetsons it is the power
    mode's budget, an upper bound); 1 on a GPU or an NPU (``busy_w`` is the board with that
    unit busy), and where the deployment or the unit is unknown."""
    if dep is None or unit is None or dep.target != "cpu" or getattr(unit, "cores", 0) <= 0:
        return 1.0
    return min(dep.threads or unit.cores, unit.cores) / unit.cores


def thread_share(dep: Deployment, unit, parallel: float) -> float:
    """The share of the threads' summed peak a CPU deployment reaches: n threads run as
    ``1 + (n - 1) * parallel`` of one (1 on other units, or at ``parallel`` = 1)."""
    if dep.target != "cpu" or unit.cores <= 1:
        return 1.0
    n = min(dep.threads or unit.cores, unit.cores)
    return (1.0 + (n - 1) * parallel) / n


def param_stream(nbytes: float, held: float, cache: float) -> tuple[float, float]:
    """(bytes streamed at every inference, bytes held after) of a layer's ``nbytes`` of
    parameters on an accelerator whose ``cache`` bytes of on-chip memory already hold
    ``held``: the compiler caches the parameters in the network's order until the memory is
    full, and the rest stream from the host's memory at every inference (Coral, "Edge TPU
    Compiler": models "share the Edge TPU's RAM for parameter data caching"; arXiv 2503.01025,
    abstract: "given the limited amount of on-chip memory on the Edge TPU, accesses to
    external (host) memory rapidly become an important performance bottleneck")."""
    fits = max(0.0, min(nbytes, cache - held))
    return nbytes - fits, held + fits


def peak_macs(dep: Deployment, unit) -> float:
    """The unit's peak MAC/s for the deployment (``compute_precision``; threads on a CPU)."""
    p, _ = compute_precision(dep, unit)
    threads = dep.threads if dep.target == "cpu" else None
    if p == "tf32":
        return max(unit.peak_macs("fp32"), unit.peak_macs("fp16") / 2.0)
    return unit.peak_macs(p, threads)


def _choice(field: str, value, allowed, where: str) -> str:
    if not isinstance(value, str) or value not in allowed:
        raise ConfigError(f"{where}{field} = {value!r} is not allowed"
                          f"{close_matches(value, allowed) if isinstance(value, str) else ''}; "
                          f"allowed: {', '.join(allowed)}")
    return value


def check_names(runtime=None, precision=None, target=None, threads=None, *,
                where: str = "") -> None:
    """Check the names alone (before a computer is known); None passes."""
    w = f"{where}: " if where else ""
    if runtime is not None:
        _choice("runtime", runtime, RUNTIMES, w)
    if precision is not None:
        _choice("precision", precision, PRECISIONS, w)
    if target is not None:
        _choice("target", target, TARGETS, w)
    if threads is not None and (isinstance(threads, bool) or not isinstance(threads, Integral)
                                or threads < 1):
        raise ConfigError(f"{w}threads = {threads!r} is not allowed; expected an int >= 1 "
                          f"(or None: the runtime's default, every core of the computer's CPU "
                          f"but for TF Lite, one)")


def resolve(device, runtime=None, precision=None, target=None, threads=None, *,
            where: str = "", quantized: str | bool | None = None,
            half: bool = False) -> Deployment:
    """The deployment on ``device`` (a ``Device``) with the defaults filled in.

    ``quantized``: the model is an int8 graph (``NetworkCost.meta["int8"]``): with no
    precision stated (by the call or the drone's defaults) it runs at int8 where the
    runtime can, else at the runtime's default precision with a ``QuantizedModelWarning``.
    ``half``: the model's weights are fp16 (``NetworkCost.meta["fp16"]``): likewise at fp16,
    else with a ``HalfModelWarning``. A float graph on the Edge TPU, which runs only
    full-integer models, is predicted at int8 with a ``ModelPrecisionWarning``.
    ConfigError for an unknown name, or for what this computer cannot run (naming the
    computer, the runtime and what it can run)."""
    check_names(runtime, precision, target, threads, where=where)
    w = f"{where}: " if where else ""
    dflt = dict(getattr(device, "defaults", ()))      # a drone's defaults for its tasks
    if dflt and runtime is None and (target is None or target == dflt.get("target", target)):
        runtime, target = dflt.get("runtime"), target or dflt.get("target")
        precision = precision or dflt.get("precision")
    if threads is None:
        threads = dflt.get("threads")
    deps = [tuple(d.split("/")) for d in device.deployments]
    if not deps:
        raise ConfigError(f"{w}device {device.name!r} has no datasheet (no runtimes listed): "
                          f"runtime/precision cannot be chosen for it")
    rts = list(dict.fromkeys(r for r, _ in deps))
    if runtime is None:
        runtime = rts[0] if target is None else next(
            (r for r, t in deps if t == target), rts[0])
    if runtime not in rts:
        why = ("it has no NVIDIA GPU" if runtime == "tensorrt" else
               "it has no Edge TPU" if runtime == "edgetpu" else "its datasheet does not list it")
        raise ConfigError(f"{w}runtime = {runtime!r} cannot run on computer {device.name!r} "
                          f"({why}); runtimes on {device.name}: {', '.join(rts)}")
    targets = [t for r, t in deps if r == runtime]
    if target is None:
        target = targets[0]
    if target not in targets:
        raise ConfigError(f"{w}target = {target!r} is not available for runtime {runtime!r} on "
                          f"computer {device.name!r}; allowed: {', '.join(targets)}")
    unit = device.unit(target)
    precs = [p for p in unit.precisions if p in RUNTIME_PRECISIONS[runtime]]
    # the graph's own precision (an int8 or an fp16 graph runs its own kernels) where the
    # deployment runs it
    own, what, cls = (("int8", f" is quantized (int8, {quantized})", QuantizedModelWarning)
                      if quantized else ("fp16", "'s weights are fp16", HalfModelWarning)
                      if half else (None, "", None))
    if precision is None and own is not None:
        if own in precs:
            precision = own
        else:
            warnings.warn(f"{w}the model{what} but runtime {runtime!r} on the {target} of "
                          f"computer {device.name!r} cannot run {own} (allowed there: "
                          f"{', '.join(precs) or 'none'}); predicted at the runtime's default "
                          f"precision", cls, stacklevel=3)
    if precision is None and runtime == "edgetpu" and not quantized:
        warnings.warn(f"{w}the model is a float graph; the Edge TPU runs only full-integer "
                      f"(int8) models compiled by its compiler: predicted as if quantized to "
                      f"int8", ModelPrecisionWarning, stacklevel=3)
    if precision is None:       # what the runtime runs by default: fp32 but on TensorRT/Edge TPU
        precision = ("fp32" if "fp32" in precs and runtime not in ("tensorrt", "edgetpu")
                     else precs[0] if precs else unit.precisions[0])
    if precision not in precs:
        raise ConfigError(f"{w}precision = {precision!r} cannot run with runtime {runtime!r} "
                          f"on the {target} of computer {device.name!r}; allowed there: "
                          f"{', '.join(precs) or 'none'}")
    if threads is not None and target == "cpu" and threads > unit.cores:
        raise ConfigError(f"{w}threads = {threads!r} is not allowed on computer {device.name!r}: "
                          f"its CPU has {unit.cores} cores; expected 1..{unit.cores}")
    if threads is None and target == "cpu":
        threads = DEFAULT_THREADS.get(runtime)
    return Deployment(runtime, target, precision, None if threads is None else int(threads))


__all__ = ["BYTES", "DEFAULT_THREADS", "FP16_ON_ARMV82", "PRECISIONS", "RUNTIMES", "RUNTIME_PRECISIONS", "RUNTIME_TARGETS", "TARGETS",
           "TF32_BY_DEFAULT", "Deployment", "HalfModelWarning", "ModelPrecisionWarning",
           "QuantizedModelWarning", "check_names", "compute_precision", "param_stream", "peak_macs",
           "power_share", "resolve", "thread_share"]
