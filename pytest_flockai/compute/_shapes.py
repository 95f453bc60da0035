"""Tensor shapes through a whole ONNX graph (the engine behind ``graph.analyze``).

First ``onnx.shape_inference`` with data propagation (shape arithmetic such as
``Shape -> Gather -> Concat -> Reshape`` is evaluated). Where a node output is still
without a full static shape (torch exports whose ``Split`` sizes or ``Resize`` scales
come from computed tensors), one ONNX Runtime run of the graph, with every unknown
intermediate exposed as an output and zeros fed to the inputs, reads the rest. Both
need concrete graph input shapes: ``fix_input_shapes`` sets them.
"""

from __future__ import annotations

import os

import numpy as np
import onnx
import onnxruntime as ort
from onnx import TensorProto

from ..errors import ConfigError

Shape = tuple[int, ...]


def load_onnx(path) -> onnx.ModelProto:
    """Load an ONNX file; ConfigError naming the path when missing or corrupt."""
    p = os.fspath(path)
    if not os.path.isfile(p):
        raise ConfigError(f"model path = {p!r} does not exist or is not a file; "
                          f"expected an .onnx file")
    try:
        return onnx.load(p)
    except Exception as e:  # DecodeError, ValueError, ...
        raise ConfigError(f"model path = {p!r} is not a valid ONNX model: "
                          f"{type(e).__name__}: {e}") from None


def graph_inputs(model: onnx.ModelProto) -> list:
    """The graph inputs that are not initializers (the tensors a caller feeds)."""
    inits = {i.name for i in model.graph.initializer}
    return [i for i in model.graph.input if i.name not in inits]


def fix_input_shapes(model, shapes: dict | None = None):
    """A copy of ``model`` whose graph inputs have concrete dims.

    ``shapes`` maps input name -> full shape; otherwise unknown dims become 1
    (batch) and anything else unknown stays unknown.
    """
    m = onnx.ModelProto()
    m.CopyFrom(model)
    names = [i.name for i in graph_inputs(m)]
    for key in shapes or {}:
        if key not in names:
            raise ConfigError(f"input_shape: input name {key!r} is not an input of the model; "
                              f"its inputs: {names}")
    for inp in graph_inputs(m):
        dims = inp.type.tensor_type.shape.dim
        want = (shapes or {}).get(inp.name)
        if want is not None:
            if len(want) != len(dims):
                raise ConfigError(f"input {inp.name!r}: shape {tuple(want)} has rank {len(want)}; "
                                  f"the model's input has rank {len(dims)}")
            for d, v in zip(dims, want):
                if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
                    raise ConfigError(f"input {inp.name!r}: shape {tuple(want)} is not allowed; "
                                      f"expected whole numbers >= 1")
                d.ClearField("dim_param")
                d.dim_value = int(v)
        elif len(dims) and not (dims[0].HasField("dim_value") and dims[0].dim_value > 0):
            dims[0].ClearField("dim_param")
            dims[0].dim_value = 1
    return m


def static_shape(type_proto) -> Shape | None:
    """Full static shape of a tensor type, or None when any dim is unknown."""
    if not type_proto.HasField("tensor_type"):
        return None
    t = type_proto.tensor_type
    if not t.HasField("shape"):
        return None
    out = []
    for d in t.shape.dim:
        if not (d.HasField("dim_value") and d.dim_value >= 0) or d.HasField("dim_param"):
            return None
        out.append(int(d.dim_value))
    return tuple(out)


def constant_shapes(model: onnx.ModelProto) -> dict[str, Shape]:
    """Shapes of initializers and ``Constant`` node outputs."""
    shapes: dict[str, Shape] = {t.name: tuple(int(d) for d in t.dims)
                                for t in model.graph.initializer}
    for node in model.graph.node:
        if node.op_type == "Constant" and node.domain in ("", "ai.onnx"):
            for a in node.attribute:
                if a.name == "value":
                    shapes[node.output[0]] = tuple(int(d) for d in a.t.dims)
                elif a.name in ("value_float", "value_int"):
                    shapes[node.output[0]] = ()
                elif a.name in ("value_floats", "value_ints"):
                    shapes[node.output[0]] = (len(onnx.helper.get_attribute_value(a)),)
    return shapes


def infer_shapes(fixed: onnx.ModelProto, *, runtime: bool = True) -> tuple[dict, str, str | None]:
    """(shape of every known tensor, how they were found, error text or None).

    ``how`` is ``"onnx"`` (shape inference alone), ``"onnx+onnxruntime"`` (the run
    filled the gaps) or ``"onnx (onnxruntime run failed)"``.
    """
    error = None
    try:
        inferred = onnx.shape_inference.infer_shapes(fixed, strict_mode=False, data_prop=True)
    except Exception as e:  # an inconsistent graph: keep the declared shapes
        inferred, error = fixed, f"shape inference failed: {type(e).__name__}: {e}"
    g = inferred.graph
    shapes: dict[str, Shape] = {}
    for vi in list(g.input) + list(g.value_info) + list(g.output):
        s = static_shape(vi.type)
        if s is not None:
            shapes[vi.name] = s
    shapes.update(constant_shapes(fixed))
    missing = [o for n in fixed.graph.node for o in n.output if o and o not in shapes]
    how = "onnx"
    if missing and runtime:
        got, run_error = _run_shapes(fixed, missing)
        shapes.update(got)
        if run_error is None:
            how = "onnx+onnxruntime"
        else:
            how = "onnx (onnxruntime run failed)"
            error = run_error if error is None else f"{error}; {run_error}"
    return shapes, how, error


_NP = {TensorProto.FLOAT: np.float32, TensorProto.FLOAT16: np.float16,
       TensorProto.DOUBLE: np.float64, TensorProto.UINT8: np.uint8, TensorProto.INT8: np.int8,
       TensorProto.INT32: np.int32, TensorProto.INT64: np.int64, TensorProto.BOOL: np.bool_}


def _run_shapes(fixed: onnx.ModelProto, names: list[str]) -> tuple[dict, str | None]:
    """Shapes of ``names`` read off one ONNX Runtime run fed with zeros."""
    feeds: dict[str, np.ndarray] = {}
    for inp in graph_inputs(fixed):
        shape = static_shape(inp.type)
        elem = inp.type.tensor_type.elem_type
        if shape is None:
            return {}, (f"input {inp.name!r} has no full static shape; give input_shape "
                        f"to read the intermediate shapes with onnxruntime")
        if elem not in _NP:
            return {}, f"input {inp.name!r} has element type {elem}, not a numeric tensor"
        feeds[inp.name] = np.zeros(shape, _NP[elem])
    m = onnx.ModelProto()
    m.CopyFrom(fixed)
    have = {o.name for o in m.graph.output}
    m.graph.output.extend(onnx.ValueInfoProto(name=n) for n in names if n not in have)
    opts = ort.SessionOptions()
    opts.graph_optimization_level = ort.GraphOptimizationLevel.ORT_DISABLE_ALL
    opts.log_severity_level = 3
    opts.intra_op_num_threads = 1
    try:
        sess = ort.InferenceSession(m.SerializeToString(), opts,
                                    providers=["CPUExecutionProvider"])
        outs = sess.get_outputs()
        values = sess.run([o.name for o in outs], feeds)
    except Exception as e:
        return {}, f"onnxruntime run for shapes failed: {type(e).__name__}: {_clip(str(e))}"
    return {o.name: tuple(int(d) for d in np.shape(v)) for o, v in zip(outs, values)}, None


def _clip(text: str, head: int = 100, tail: int = 240) -> str:
    """``text`` cut to its start and its end (ONNX Runtime's reason comes last, after the
    node's name, which exporters such as tf2onnx make hundreds of characters long)."""
    text = " ".join(text.split())
    return text if len(text) <= head + tail + 5 else f"{text[:head]} ... {text[-tail:]}"


__all__ = ["constant_shapes", "fix_input_shapes", "graph_inputs", "infer_shapes", "load_onnx",
           "static_shape"]
