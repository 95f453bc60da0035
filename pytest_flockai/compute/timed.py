"""The runtimes ``flockai profile-device`` times a model with, each behind one call.

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
  it is read back and recorded (``Runner.execution``);
- ``ncnn``: an ncnn model (``MODEL.param`` with ``MODEL.bin`` beside it, as ``pnnx`` or
  ``onnx2ncnn`` writes them) in ncnn's Python binding, at ``threads``, on the CPU (ncnn's
  own defaults: fp16 storage and arithmetic where the CPU has them, recorded), or on the
  GPU through Vulkan (``target="gpu"``); its input shape comes from ``--input-shape`` or
  the ONNX file it stands for (ncnn's files do not hold it), batch 1;
- ``tflite`` and ``edgetpu``: a ``.tflite`` file (the format these runtimes run; an
  ONNX file is refused) in LiteRT's ``Interpreter`` (``ai_edge_litert``, else
  ``tflite_runtime``, else ``tensorflow.lite``), on the CPU with XNNPACK at ``threads``,
  or with the Edge TPU's delegate (``libedgetpu.so.1``) for a model compiled by
  ``edgetpu_compiler``.

OpenVINO, ncnn and LiteRT are optional dependencies: without them, their ``--runtime`` is a
ConfigError saying how to get them.
"""

from __future__ import annotations

import ctypes
import importlib.metadata
import os
from collections.abc import Callable
from dataclasses import dataclass, field

import cv2
import numpy as np
import onnx
import onnxruntime as ort

from ..errors import ConfigError
from ._shapes import graph_inputs
from .profile import model_format

#: runtimes profile-device times
MEASURABLE = ("onnxruntime", "opencv-dnn", "openvino", "ncnn", "tflite", "edgetpu")
#: the file format each runtime runs (the rest run the ONNX file itself)
FORMAT = {"tflite": "tflite", "edgetpu": "tflite", "ncnn": "ncnn"}
#: what each format's files are called
SUFFIX = {"onnx": ".onnx", "tflite": ".tflite", "ncnn": ".param (with its .bin)"}
#: the Edge TPU delegate's shared library (Coral's libedgetpu, Linux)
EDGETPU_LIB = "libedgetpu.so.1"
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
    return {"opencv-dnn": ("cpu",), "tflite": ("cpu",), "edgetpu": ("npu",)}.get(
        runtime, ("cpu", "gpu"))


def runner(path, runtime: str, target: str, threads: int | None, shape, seed: int) -> Runner:
    """``path`` loaded by ``runtime`` (see the module docstring); ``shape`` fills the
    input's open dims (fixed ones stay); ``seed``: the input tensor's."""
    fmt, want = model_format(path), FORMAT.get(runtime, "onnx")
    if fmt != want:
        what = {"tflite": "a TF Lite (.tflite)", "ncnn": "an ncnn (.param)"}.get(fmt, "an ONNX")
        by = sorted(r for r in MEASURABLE if FORMAT.get(r, "onnx") == fmt)
        raise ConfigError(f"model {os.fspath(path)!r} is {what} file; --runtime {runtime} runs "
                          f"{SUFFIX[want]} files ({what} file: --runtime {' or '.join(by)})")
    if fmt == "tflite":
        return _tflite(os.fspath(path), runtime, threads, shape, seed)
    if fmt == "ncnn":
        return _ncnn(os.fspath(path), target, threads, shape, seed)
    inp, dims = onnx_input(path)
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


def onnx_input(path) -> tuple:
    """(the input a caller feeds, its dims with None where open) of an ONNX file's first
    graph input that is not an initializer."""
    proto = onnx.load(os.fspath(path), load_external_data=False)
    inp = graph_inputs(proto)[0]
    return inp, [d.dim_value if d.HasField("dim_value") and d.dim_value > 0 else None
                 for d in inp.type.tensor_type.shape.dim]


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


#: the process's one OpenVINO Core: made once and kept, as OpenVINO advises (a Core's
#: destruction unloads its device plugins; a process that went on to fly with a SIGALRM
#: watchdog was seen to crash in the signal handler after that, OpenVINO 2026.4)
_CORE: list = []


def _ov_core(ov):
    if not _CORE:
        _CORE.append(ov.Core())
    return _CORE[0]


def _openvino(path, name, x, target, threads) -> Runner:
    try:
        import openvino as ov
    except ImportError:
        raise ConfigError("--runtime = 'openvino' is not allowed here: OpenVINO is not "
                          "installed in this environment (pip install openvino)") from None
    core = _ov_core(ov)
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


def _ncnn(path, target, threads, shape, seed) -> Runner:
    try:
        import ncnn
    except ImportError:
        raise ConfigError("--runtime = 'ncnn' is not allowed here: ncnn's Python binding is "
                          "not installed in this environment (pip install ncnn)") from None
    weights = path[:-len(".param")] + ".bin"
    if not os.path.isfile(weights):
        raise ConfigError(f"model {path!r}: its weights {weights!r} do not exist; an ncnn "
                          f"model is a .param file with its .bin beside it")
    if shape is None:
        raise ConfigError(f"model {path!r}: ncnn's files do not hold the input shape; give "
                          f"--input-shape (e.g. 1x3x640x640) or --onnx")
    if len(shape) not in (3, 4) or (len(shape) == 4 and shape[0] != 1):
        raise ConfigError(f"--input-shape = {'x'.join(map(str, shape))!r} is not allowed for "
                          f"ncnn; expected 1xCxHxW (batch 1) or CxHxW")
    net = ncnn.Net()
    if threads is not None:
        net.opt.num_threads = threads
    if target == "gpu":
        if ncnn.get_gpu_count() < 1:
            raise ConfigError(f"--target = 'gpu' is not allowed here: ncnn "
                              f"{ncnn.__version__} finds no Vulkan GPU")
        net.opt.use_vulkan_compute = True
    if net.load_param(path) != 0 or net.load_model(weights) != 0:
        raise ConfigError(f"model {path!r}: --runtime ncnn ({ncnn.__version__}) cannot load "
                          f"it (or its {os.path.basename(weights)})")
    inp, out = net.input_names()[0], net.output_names()[0]
    chw = tuple(int(d) for d in shape[-3:])
    x = np.ascontiguousarray(np.random.default_rng(seed).random(chw).astype(np.float32))
    mat = ncnn.Mat(x)

    def run_ncnn():
        ex = net.create_extractor()         # an extractor keeps its blobs: one per run
        ex.input(inp, mat)
        ex.extract(out)
    o = net.opt
    execution = {"threads": int(o.num_threads), "vulkan": bool(o.use_vulkan_compute),
                 "fp16_storage": bool(o.use_fp16_storage),
                 "fp16_arithmetic": bool(o.use_fp16_arithmetic),
                 "precision": "int8" if _ncnn_int8(path) else "fp32"}
    return Runner(run_ncnn, (1, *chw), str(ncnn.__version__), execution)


def _ncnn_int8(path) -> bool:
    """An ncnn graph quantized by ncnn2int8: a Convolution or InnerProduct layer with an
    int8 scale term (parameter 8)."""
    with open(path, encoding="utf-8", errors="replace") as fh:
        return any(line.split()[:1] and line.split()[0].startswith(("Convolution", "InnerProduct"))
                   and any(t.startswith("8=") and t != "8=0" for t in line.split()[4:])
                   for line in fh)


def _interpreter():
    """LiteRT's (Interpreter, load_delegate, package name), whichever is installed."""
    try:
        from ai_edge_litert.interpreter import Interpreter, load_delegate
        return Interpreter, load_delegate, "ai-edge-litert"
    except ImportError:
        pass
    try:
        from tflite_runtime.interpreter import Interpreter, load_delegate
        return Interpreter, load_delegate, "tflite-runtime"
    except ImportError:
        pass
    try:
        import tensorflow as tf
        return tf.lite.Interpreter, tf.lite.experimental.load_delegate, "tensorflow"
    except ImportError:
        raise ConfigError("--runtime tflite/edgetpu is not allowed here: no LiteRT is "
                          "installed in this environment (pip install ai-edge-litert, or "
                          "tflite-runtime)") from None


def _tflite(path, runtime, threads, shape, seed) -> Runner:
    interpreter, load_delegate, package = _interpreter()
    version = importlib.metadata.version(package)
    delegates = []
    if runtime == "edgetpu":
        try:
            ctypes.CDLL(EDGETPU_LIB)        # first: a failed load_delegate leaves a bad object
            delegates = [load_delegate(EDGETPU_LIB)]
        except (ValueError, OSError) as e:
            raise ConfigError(f"--runtime = 'edgetpu' is not allowed here: the Edge TPU "
                              f"delegate {EDGETPU_LIB} does not load ({str(e).strip()[:160]})") from None
    try:
        it = interpreter(model_path=path, num_threads=threads, experimental_delegates=delegates)
        inp = it.get_input_details()[0]
        dims = [int(d) for d in inp["shape"]]
        if shape is not None:
            if len(shape) != len(dims):
                raise ConfigError(f"--input-shape = {'x'.join(map(str, shape))!r} has rank "
                                  f"{len(shape)}; {path!r} input {inp['name']!r} has rank {len(dims)}")
            if list(shape) != dims:
                it.resize_tensor_input(inp["index"], list(shape))
                dims = list(shape)
        it.allocate_tensors()
    except (ValueError, RuntimeError) as e:
        raise ConfigError(f"model {path!r}: --runtime {runtime} ({package} {version}) cannot "
                          f"load it: {str(e).strip()[:200]}") from None
    rng = np.random.default_rng(seed)
    dtype = np.dtype(inp["dtype"])
    x = (rng.integers(0, 128, dims).astype(dtype) if dtype.kind in "iu"
         else rng.random(dims).astype(dtype))
    index, invoke, set_tensor = inp["index"], it.invoke, it.set_tensor

    def run_tflite():
        set_tensor(index, x)
        invoke()
    quantized = dtype.kind in "iu" or any(
        np.dtype(t["dtype"]) == np.int8 for t in it.get_tensor_details())
    execution = {"package": package, "precision": "int8" if quantized or delegates else "fp32",
                 "delegate": EDGETPU_LIB if delegates else "default (XNNPACK)"}
    return Runner(run_tflite, tuple(dims), version, execution)


__all__ = ["EDGETPU_LIB", "FORMAT", "MEASURABLE", "OV_PRECISION", "SUFFIX", "Runner",
           "onnx_input", "runner", "targets"]
