"""The runtimes ``flockai profile-device`` times an ONNX model with, each behind one call.

``runner(path, runtime, target, threads, shape, seed) -> Runner``: the model loaded by
the runtime, a seeded input of its shape, and a call that runs one inference:

- ``onnxruntime``: an ``InferenceSession`` on the CPU provider (``target="gpu"``: the CUDA
  provider first, where this build has it);
- ``opencv-dnn``: ``cv2.dnn.readNetFromONNX`` on the CPU;
- ``openvino``: ``Core.read_model`` of the ONNX file (OpenVINO reads ONNX itself: the
  profiled file is the one a task flies, so its SHA-256 matches), compiled with the
  ``LATENCY`` performance hint for ``CPU`` (``target="gpu"``: OpenVINO's ``GPU`` device
  where this computer has one). OpenVINO picks the precision it computes in
  (``INFERENCE_PRECISION_HINT``: bf16 on x86 CPUs with AMX or AVX-512 BF16, f16 on ARM);
  it is read back and recorded (``Runner.execution``). OpenVINO is an optional
  dependency: without it, ``--runtime openvino`` is a ConfigError saying how to get it.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass, field

import cv2
import numpy as np
import onnx
import onnxruntime as ort

from ..errors import ConfigError

#: runtimes profile-device times (each reads the ONNX file itself)
MEASURABLE = ("onnxruntime", "opencv-dnn", "openvino")
#: OpenVINO's element types -> the profile's precision (bf16 and f16 both compute in 16 bits)
OV_PRECISION = {"f32": "fp32", "f16": "fp16", "bf16": "fp16", "i8": "int8", "u8": "int8"}


@dataclass(frozen=True)
class Runner:
    """One model loaded by one runtime: ``run()`` runs an inference on ``input_shape``."""

    run: Callable[[], object]
    input_shape: tuple[int, ...]
    version: str
    #: what the runtime reports it computes with (OpenVINO: ``precision``, ``device``)
    execution: dict = field(default_factory=dict)


def targets(runtime: str) -> tuple[str, ...]:
    return ("cpu",) if runtime == "opencv-dnn" else ("cpu", "gpu")


def runner(path, runtime: str, target: str, threads: int | None, shape, seed: int) -> Runner:
    """``path`` loaded by ``runtime`` (see the module docstring); ``shape`` fills the
    input's open dims (fixed ones stay); ``seed``: the input tensor's."""
    proto = onnx.load(os.fspath(path), load_external_data=False)
    inits = {i.name for i in proto.graph.initializer}
    inp = next(i for i in proto.graph.input if i.name not in inits)
    dims = [d.dim_value if d.HasField("dim_value") and d.dim_value > 0 else None
            for d in inp.type.tensor_type.shape.dim]
    if shape is not None:       # it fills the dims the model leaves open; fixed dims stay
        if len(shape) != len(dims):
            raise ConfigError(f"--input-shape = {'x'.join(map(str, shape))!r} has rank "
                              f"{len(shape)}; {str(path)!r} input {inp.name!r} has rank {len(dims)}")
        dims = [g if d is None else d for d, g in zip(dims, shape)]
    elif dims and dims[0] is None:
        dims[0] = 1
    if any(d is None for d in dims):
        raise ConfigError(f"model {str(path)!r}: input {inp.name!r} has dims "
                          f"{[d or '?' for d in dims]}; give --input-shape")
    full = tuple(int(d) for d in dims if d is not None)
    rng = np.random.default_rng(seed)
    elem = inp.type.tensor_type.elem_type
    dtype = {onnx.TensorProto.FLOAT16: np.float16, onnx.TensorProto.UINT8: np.uint8,
             onnx.TensorProto.INT8: np.int8}.get(elem, np.float32)
    x = (rng.integers(0, 128, full).astype(dtype) if dtype in (np.uint8, np.int8)
         else rng.random(full).astype(dtype))
    make = {"opencv-dnn": _opencv, "openvino": _openvino}.get(runtime, _onnxruntime)
    return make(os.fspath(path), inp.name, x, target, threads)


def _opencv(path, name, x, target, threads) -> Runner:
    try:
        net = cv2.dnn.readNetFromONNX(path)
    except cv2.error as e:
        raise ConfigError(f"model {path!r}: --runtime opencv-dnn ({cv2.__version__}) "
                          f"cannot load it: {str(e).strip()[-200:]}") from None
    if threads is not None:
        cv2.setNumThreads(threads)

    def run_cv():
        net.setInput(x)
        net.forward()
    return Runner(run_cv, tuple(x.shape), cv2.__version__)


def _onnxruntime(path, name, x, target, threads) -> Runner:
    opts = ort.SessionOptions()
    if threads is not None:
        opts.intra_op_num_threads = threads
    providers = ["CPUExecutionProvider"]
    if target == "gpu":
        if "CUDAExecutionProvider" not in ort.get_available_providers():
            raise ConfigError(f"--target = 'gpu' is not allowed here: onnxruntime "
                              f"{ort.__version__} has providers {ort.get_available_providers()}")
        providers.insert(0, "CUDAExecutionProvider")
    try:
        sess = ort.InferenceSession(path, opts, providers=providers)
    except Exception as e:  # noqa: BLE001 (onnxruntime's own exception types)
        raise ConfigError(f"model {path!r}: --runtime onnxruntime ({ort.__version__}) "
                          f"cannot load it: {str(e).strip()[:200]}") from None
    feeds = {name: x}
    return Runner(lambda: sess.run(None, feeds), tuple(x.shape), ort.__version__,
                  {"providers": sess.get_providers()})


def _openvino(path, name, x, target, threads) -> Runner:
    try:
        import openvino as ov
    except ImportError:
        raise ConfigError("--runtime = 'openvino' is not allowed here: OpenVINO is not "
                          "installed in this environment (pip install openvino)") from None
    core = ov.Core()
    device = "GPU" if target == "gpu" else "CPU"
    if device not in core.available_devices:
        raise ConfigError(f"--target = {target!r} is not allowed here: OpenVINO "
                          f"{ov.__version__} has devices {core.available_devices}")
    try:
        model = core.read_model(path)
        model.reshape({name: ov.PartialShape(list(x.shape))})
        config: dict = {"PERFORMANCE_HINT": "LATENCY"}
        if threads is not None:
            config["INFERENCE_NUM_THREADS"] = threads
        compiled = core.compile_model(model, device, config)
    except RuntimeError as e:
        raise ConfigError(f"model {path!r}: --runtime openvino ({ov.__version__}) cannot load "
                          f"it: {str(e).strip()[:200]}") from None
    request = compiled.create_infer_request()
    feeds = {name: x}
    hint = compiled.get_property("INFERENCE_PRECISION_HINT")
    execution = {"device": device, "precision": hint.get_type_name(),
                 "threads": int(compiled.get_property("INFERENCE_NUM_THREADS"))}
    return Runner(lambda: request.infer(feeds), tuple(x.shape), ov.__version__, execution)


__all__ = ["MEASURABLE", "OV_PRECISION", "Runner", "runner", "targets"]
