"""Models: one calling convention, ``model(frame) -> prediction``.

Every model has ``macs`` (multiply-accumulates per inference, int, or None when unknown),
``params`` (parameter count) and ``name``. ``macs_for(frame)`` gives the MACs for a given frame
(fully-convolutional ONNX models fed at the frame's native size cost more on bigger frames; their
``macs`` is the cost at the reference 320 x 240 frame, ``REFERENCE_HW``, and latency uses
``macs_for``).

- ``OnnxModel``: an ONNX file run with ONNX Runtime; the frame is preprocessed from what the
  model's input declares (size, layout, dtype).
- ``OpenCVModel``: a classical OpenCV pipeline, ``fn(frame) -> prediction``, with the
  MAC-equivalent cost stated by the user.
- ``PythonModel``: any Python function.

Frames are uint8 ``H x W x 3`` arrays in RGB order (the camera renders RGB), or ``H x W``
greyscale."""

from __future__ import annotations

import math
import os
from numbers import Integral, Real
from pathlib import Path

import cv2
import numpy as np
import onnx
import onnxruntime as ort

from .. import memo
from ..errors import ConfigError
from .macs import _param_count, count_macs

_FLOAT_TYPES = {"tensor(float)": np.float32, "tensor(float16)": np.float16,
                "tensor(double)": np.float64}
_INT_TYPES = {"tensor(uint8)": np.uint8}


#: (height, width) at which a model with a dynamic input size reports ``macs``
REFERENCE_HW = (240, 320)


def _check_macs(macs, where: str, *, allow_none: bool):
    if macs is None:
        if allow_none:
            return None
        raise ConfigError(f"{where}: macs = None is not allowed; expected an int >= 0 "
                          f"(multiply-accumulates per inference)")
    try:
        ok = not isinstance(macs, bool) and isinstance(macs, Real) and math.isfinite(float(macs))
    except (OverflowError, TypeError, ValueError):   # an int too big for a float, ...
        ok = False
    if not ok or macs < 0:
        raise ConfigError(f"{where}: macs = {macs!r} is not allowed; expected an int >= 0 "
                          f"(multiply-accumulates per inference)")
    return int(macs)


class Model:
    """Base of every model: ``__call__(frame)``, ``macs``, ``params``, ``name``."""

    macs: int | None = None
    params: int = 0
    name: str = "model"

    def __call__(self, frame):  # pragma: no cover - interface
        raise NotImplementedError

    def macs_for(self, frame) -> int | None:
        """Multiply-accumulates of one inference on ``frame`` (None: unknown)."""
        return self.macs

    def describe(self) -> dict:
        """JSON-ready description: name, type, MACs and parameters."""
        return {"name": self.name, "type": type(self).__name__, "macs": self.macs,
                "params": self.params}

    def __repr__(self):
        return f"{type(self).__name__}({self.name!r}, macs={self.macs}, params={self.params})"


class PythonModel(Model):
    """Any Python callable ``fn(frame) -> prediction``.

    ``macs=None`` (unknown) only works with ``latency="measured"`` tasks.
    """

    def __init__(self, fn, *, macs=None, params: int = 0, name: str | None = None):
        if not callable(fn):
            raise ConfigError(f"PythonModel: fn = {fn!r} is not callable; expected fn(frame) -> prediction")
        self.fn = fn
        self.name = name or str(getattr(fn, "__name__", "python-model"))
        self.macs = _check_macs(macs, f"PythonModel {self.name!r}", allow_none=True)
        if isinstance(params, bool) or not isinstance(params, Integral) or params < 0:
            raise ConfigError(f"PythonModel {self.name!r}: params = {params!r} is not allowed; "
                              f"expected an int >= 0")
        self.params = int(params)

    def __call__(self, frame):
        return self.fn(frame)


class OpenCVModel(PythonModel):
    """A classical OpenCV pipeline ``fn(frame) -> prediction``; ``macs`` is required.

    State the cost as MAC-equivalents per inference, e.g. for a blob pipeline on
    640x480 frames: ~30 ops per pixel (colour conversion, blur, threshold,
    contours) -> ``macs=30 * 640 * 480``.
    """

    def __init__(self, fn, *, macs, params: int = 0, name: str | None = None):
        _check_macs(macs, f"OpenCVModel {name or getattr(fn, '__name__', '?')!r}", allow_none=False)
        super().__init__(fn, macs=macs, params=params, name=name or getattr(fn, "__name__", "opencv-model"))


class OnnxModel(Model):
    """An ONNX model run with ONNX Runtime on frames.

    Preprocessing follows the model's single input (it must be a rank-4 image
    tensor, float or uint8):

    - size: the input's fixed H and W; if they are dynamic, ``input_size``
      ``(height, width)``, or the frame's own size when ``input_size`` is None
      (fully-convolutional models). Frames are resized with ``cv2.resize``
      (INTER_AREA when shrinking, INTER_LINEAR when enlarging).
    - layout: ``"NCHW"`` or ``"NHWC"``, guessed from where the 1- or 3-sized
      channel dimension is; pass ``layout=`` when it is ambiguous.
    - channels: 3 (RGB, as rendered) or 1 (converted to grey).
    - values: uint8 inputs get the raw pixels; float inputs get
      ``(pixel * scale - mean) / std`` with ``scale`` 1/255, ``mean`` 0 and
      ``std`` 1 by default (``mean``/``std`` may be per channel).

    The prediction is the output array with the batch dimension removed (a
    tuple of them when the model has several outputs), passed through
    ``postprocess`` if given. ``macs``/``params`` come from the ONNX graph
    (``pytest_flockai.ml.macs``) unless ``macs=`` is given.
    """

    def __init__(self, path, *, input_size=None, layout=None, scale=None, mean=None, std=None,
                 providers=("CPUExecutionProvider",), macs=None, postprocess=None,
                 threads: int = 1, name: str | None = None):
        if not isinstance(path, (str, os.PathLike)):
            raise ConfigError(f"OnnxModel: path = {path!r} is not allowed; expected the path of "
                              f"an .onnx file")
        self.path = os.fspath(path)
        self.name = name or os.path.splitext(os.path.basename(self.path))[0]
        where = f"OnnxModel {self.path!r}"
        if not os.path.isfile(self.path):
            raise ConfigError(f"model path = {self.path!r} does not exist or is not a file; "
                              f"expected an .onnx file")
        # by path, never by bytes: external data (weights.bin beside the model) then
        # resolves from the model's folder, not from the working directory
        self._providers, self._threads = tuple(providers), int(threads)
        self.session = self._session(self.path, providers, threads)
        self._layout_arg = layout
        if postprocess is not None and not callable(postprocess):
            raise ConfigError(f"{where}: postprocess = {postprocess!r} is not callable")
        self.postprocess = postprocess
        inp, dims, shp = self._input(where)
        hi, wi = (2, 3) if self.layout == "NCHW" else (1, 2)
        self.input_size = self._input_size(input_size, dims, shp, hi, wi, where, inp.name)
        self._normalisation(scale, mean, std, where, inp.name)
        self._costs(macs, where)

    def __getstate__(self) -> dict:
        """Pickled/deep-copied (sweeps, workers) without the session: re-opened from the path."""
        state = self.__dict__.copy()
        state["session"] = None
        state["_proto"] = self._proto is not None
        return state

    def __setstate__(self, state: dict) -> None:
        had_proto = state.pop("_proto")
        self.__dict__.update(state)
        self.session = self._session(self.path, self._providers, self._threads)
        self._proto = self._load_proto(self.path) if had_proto else None

    def _session(self, path, providers, threads):
        opts = ort.SessionOptions()
        opts.intra_op_num_threads = int(threads)
        opts.inter_op_num_threads = 1
        opts.log_severity_level = 3
        try:
            return ort.InferenceSession(path, opts, providers=list(providers))
        except Exception as e:
            raise ConfigError(f"model path = {self.path!r} is not a valid ONNX model "
                              f"(ONNX Runtime: {type(e).__name__}: {str(e).strip()[:300]})") from None

    def _input(self, where):
        """The one image input: its dtype, layout and channels; (input, dims, shape)."""
        inputs = self.session.get_inputs()
        if len(inputs) != 1:
            raise ConfigError(f"{where}: the model has {len(inputs)} inputs "
                              f"({', '.join(i.name for i in inputs)}); a frame can feed exactly one "
                              f"image input")
        inp = inputs[0]
        self.input_name = inp.name
        if inp.type in _FLOAT_TYPES:
            self._dtype = _FLOAT_TYPES[inp.type]
        elif inp.type in _INT_TYPES:
            self._dtype = np.uint8
        else:
            raise ConfigError(f"{where}: input {inp.name!r} has type {inp.type}; a frame can feed "
                              f"float or uint8 image tensors only")
        shp = list(inp.shape)
        if len(shp) != 4:
            raise ConfigError(f"{where}: input {inp.name!r} has shape {shp} (rank {len(shp)}); "
                              f"a frame can feed rank-4 image tensors only (N, C, H, W or N, H, W, C)")
        dims = [d if isinstance(d, int) and d > 0 else None for d in shp]
        if dims[0] not in (None, 1):
            raise ConfigError(f"{where}: input {inp.name!r} has batch size {dims[0]}; frames are fed "
                              f"one at a time (batch 1)")
        self.layout = self._layout(dims, self._layout_arg, where, inp.name)
        ci = 1 if self.layout == "NCHW" else 3
        c = dims[ci] if dims[ci] is not None else 3
        if c not in (1, 3):
            raise ConfigError(f"{where}: input {inp.name!r} has {c} channels in layout {self.layout}; "
                              f"a frame can feed 1 (grey) or 3 (RGB) channels")
        self.channels = c
        return inp, dims, shp

    @staticmethod
    def _input_size(input_size, dims, shp, hi, wi, where, name):
        if input_size is not None:
            try:
                h, w = (int(v) for v in input_size)
                if h <= 0 or w <= 0:
                    raise ValueError
            except (TypeError, ValueError):
                raise ConfigError(f"{where}: input_size = {input_size!r} is not allowed; expected "
                                  f"(height, width) in pixels") from None
            for got, want, axis in ((h, dims[hi], "height"), (w, dims[wi], "width")):
                if want is not None and got != want:
                    raise ConfigError(f"{where}: input_size = {tuple(input_size)!r} has {axis} {got} "
                                      f"but the model's input is fixed at {want}")
            return (h, w)
        if dims[hi] is not None and dims[wi] is not None:
            return (dims[hi], dims[wi])
        if dims[hi] is None and dims[wi] is None:
            return None          # native frame size
        raise ConfigError(f"{where}: input {name!r} has one fixed and one dynamic spatial "
                          f"dimension {shp}; pass input_size=(height, width)")

    def _normalisation(self, scale, mean, std, where, name):
        if self._dtype == np.uint8:
            if any(v is not None for v in (scale, mean, std)):
                raise ConfigError(f"{where}: scale/mean/std are for float inputs; input "
                                  f"{name!r} is uint8 and gets raw pixels")
            self.scale, self.mean, self.std = 1.0, None, None
            return
        self.scale = 1.0 / 255.0 if scale is None else float(scale)
        self.mean = self._per_channel("mean", mean, where)
        self.std = self._per_channel("std", std, where)
        if self.std is not None and np.any(self.std == 0):
            raise ConfigError(f"{where}: std = {std!r} has a zero entry")

    def _costs(self, macs, where):
        """``macs`` and ``params``: given, or counted from the graph."""
        self._macs_given = _check_macs(macs, where, allow_none=True)
        self._mac_cache: dict = {}
        self._proto = None
        self.mac_report = None
        if self._macs_given is not None:
            self.macs = self._macs_given
            self.params = self._params_from_graph(self.path, fail_ok=True)
            return
        self._proto = self._load_proto(self.path)
        # dynamic height/width: report the cost at the reference frame size
        # (the blueprints' 320x240 camera); latency uses macs_for(frame)
        self.macs = self._count(self.input_size if self.input_size is not None else REFERENCE_HW)
        self.params = _param_count(self._proto)

    # -- set-up helpers ------------------------------------------------------
    @staticmethod
    def _layout(dims, layout, where, name):
        if layout is not None:
            if layout not in ("NCHW", "NHWC"):
                raise ConfigError(f"{where}: layout = {layout!r} is not allowed; allowed: 'NCHW', 'NHWC'")
            return layout
        c_first, c_last = dims[1] in (1, 3), dims[3] in (1, 3)
        if c_first and not c_last:
            return "NCHW"
        if c_last and not c_first:
            return "NHWC"
        if c_first and c_last:
            return "NCHW"       # e.g. 1x3x3x3: the ONNX convention
        raise ConfigError(f"{where}: cannot tell the layout of input {name!r} with shape "
                          f"{[d if d is not None else '?' for d in dims]}; pass layout='NCHW' or 'NHWC'")

    def _per_channel(self, field, value, where):
        if value is None:
            return None
        arr = np.asarray(value, dtype=np.float32).reshape(-1)
        if arr.size not in (1, self.channels) or not np.all(np.isfinite(arr)):
            raise ConfigError(f"{where}: {field} = {value!r} is not allowed; expected a number or "
                              f"{self.channels} numbers (one per channel)")
        return arr

    def _load_proto(self, path):
        try:
            return onnx.load(path)   # external data from the model's own folder
        except Exception as e:
            raise ConfigError(f"model path = {self.path!r} is not a valid ONNX model: {e}") from None

    def _params_from_graph(self, path, fail_ok):
        try:
            return _param_count(self._load_proto(path))
        except Exception:
            if fail_ok:
                return 0
            raise

    def _count(self, hw):
        h, w = hw
        key = (h, w)
        if key not in self._mac_cache:
            shape = [1, self.channels, h, w] if self.layout == "NCHW" else [1, h, w, self.channels]
            rep = count_macs(self._proto, {self.input_name: shape})
            self._mac_cache[key] = rep.macs
            self.mac_report = rep
        return self._mac_cache[key]

    # -- running -------------------------------------------------------------
    def _target_hw(self, frame):
        if self.input_size is not None:
            return self.input_size
        a = np.asarray(frame)
        return (int(a.shape[0]), int(a.shape[1]))

    def macs_for(self, frame) -> int | None:
        if self._macs_given is not None:
            return self._macs_given
        return self._count(self._target_hw(frame))

    def preprocess(self, frame) -> np.ndarray:
        """The model's input tensor from a frame (RGB uint8, or what the task feeds)."""
        a = np.asarray(frame)
        if a.ndim == 3 and a.shape[2] == 4:
            a = a[:, :, :3]
        if not (a.ndim == 2 or (a.ndim == 3 and a.shape[2] in (1, 3))):
            raise ValueError(f"frame of shape {a.shape} is not an image (H x W or H x W x 1|3)")
        if a.dtype != np.uint8:
            a = np.clip(a, 0, 255).astype(np.uint8)
        h, w = self._target_hw(a)
        if a.shape[0] != h or a.shape[1] != w:
            shrink = h * w < a.shape[0] * a.shape[1]
            a = cv2.resize(a, (w, h), interpolation=cv2.INTER_AREA if shrink else cv2.INTER_LINEAR)
        if a.ndim == 3 and a.shape[2] == 1:
            a = a[:, :, 0]
        if self.channels == 1 and a.ndim == 3:
            a = cv2.cvtColor(a, cv2.COLOR_RGB2GRAY)
        elif self.channels == 3 and a.ndim == 2:
            a = cv2.cvtColor(a, cv2.COLOR_GRAY2RGB)
        if a.ndim == 2:
            a = a[:, :, None]
        if self._dtype == np.uint8:
            x = np.ascontiguousarray(a)
        else:
            x = a.astype(np.float32) * np.float32(self.scale)
            if self.mean is not None:
                x -= self.mean
            if self.std is not None:
                x /= self.std
            x = x.astype(self._dtype, copy=False)
        x = x.transpose(2, 0, 1)[None] if self.layout == "NCHW" else x[None]
        return np.ascontiguousarray(x)

    def run(self, x: np.ndarray):
        """Raw outputs for a preprocessed batch; memoised (``pytest_flockai.memo``) on the model
        file's bytes, the execution providers and the input's bytes."""
        inputs = {"model": Path(self.path), "providers": self.session.get_providers(),
                  "input": x}
        return memo.recall("onnx-run", inputs, lambda: self.session.run(None, {self.input_name: x}),
                           pack=lambda outs: {"outs": list(outs)},
                           unpack=lambda d: list(d["outs"]))

    def __call__(self, frame):
        outs = self.run(self.preprocess(frame))
        outs = [o[0] if getattr(o, "ndim", 0) >= 1 and o.shape[0] == 1 else o for o in outs]
        pred = outs[0] if len(outs) == 1 else tuple(outs)
        if self.macs is None and self._macs_given is None:
            self.macs = self.macs_for(frame)
        return self.postprocess(pred) if self.postprocess is not None else pred


def as_model(obj, field: str = "model") -> Model:
    """Accept a Model, a template instance or any object with ``__call__``; ConfigError otherwise."""
    if isinstance(obj, Model):
        return obj
    if callable(obj):
        if hasattr(obj, "macs"):  # duck-typed model: its macs must be a count (or None)
            _check_macs(obj.macs, f"{field} {getattr(obj, 'name', type(obj).__name__)!r}",
                        allow_none=True)
            return obj
        return PythonModel(obj)
    raise ConfigError(f"{field} = {obj!r} is not a model; expected an OnnxModel, OpenCVModel, "
                      f"PythonModel, a template subclass instance or a callable frame -> prediction")


__all__ = ["Model", "OnnxModel", "OpenCVModel", "PythonModel", "as_model"]
