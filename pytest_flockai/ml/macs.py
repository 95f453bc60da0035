"""Count multiply-accumulates (MACs) and parameters of an ONNX graph.

Shapes come from ``onnx.shape_inference`` after the graph inputs' dynamic
dimensions are fixed (batch 1, spatial size from the caller). The MAC count of
one inference is the sum over nodes:

=====================  ==================================================================
operator               MACs counted
=====================  ==================================================================
Conv                   out_elements * (C_in / group) * prod(kernel)  (grouped, depthwise
                       included: the weight's 2nd dim is C_in / group); bias not counted
ConvTranspose          in_elements * (C_out / group) * prod(kernel); bias not counted
Gemm                   M * N * K (alpha, beta and the C addend not counted)
MatMul                 out_elements * K (batched and 1-D operands per numpy rules)
MaxPool, AveragePool,  out_elements * prod(kernel_shape): every comparison or addition
LpPool                 in a window counts as one MAC-equivalent op
GlobalAverage/MaxPool  in_elements
element-wise and       out_elements (one op per output element): Add Sub Mul Div Pow
activations            Sqrt Exp Log Abs Neg Max Min Sum Mean Relu LeakyRelu PRelu Elu
                       Selu Sigmoid HardSigmoid HardSwish Tanh Softplus Clip Erf Gelu
                       Softmax LogSoftmax BatchNormalization InstanceNormalization
                       LayerNormalization Where Equal Greater Less Not And Or ...
Reduce*                in_elements
Resize, Upsample       out_elements
data movement          0: Reshape Flatten Transpose Squeeze Unsqueeze Concat Split Slice
                       Gather Identity Cast Shape Constant ConstantOfShape Dropout Pad
                       Expand Tile DepthToSpace SpaceToDepth QuantizeLinear ...
anything else          0, listed in ``MacReport.uncounted``
=====================  ==================================================================

Transcendental functions (Exp, Sigmoid, Tanh, Softmax) count one op per
element like the rest: the MAC count is a throughput proxy for device
profiles calibrated on CNNs, where Conv and Gemm dominate.

Parameters: the number of elements of the graph's floating-point and 8-bit
initializers (and of floating-point ``Constant`` nodes); int32/int64
initializers (shapes, indices, axes) are not parameters.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import onnx

from ..errors import ConfigError

ELEMENTWISE = frozenset("""
Add Sub Mul Div Pow Sqrt Exp Log Abs Neg Reciprocal Floor Ceil Round Sign Max Min Sum Mean
Relu LeakyRelu PRelu Elu Selu Celu ThresholdedRelu Sigmoid HardSigmoid HardSwish Tanh Softplus
Softsign Clip Erf Gelu Mish Sin Cos Softmax LogSoftmax BatchNormalization InstanceNormalization
LayerNormalization Where Equal Greater GreaterOrEqual Less LessOrEqual Not And Or Xor Mod
IsNaN IsInf
""".split())
REDUCE = frozenset("""ReduceMean ReduceSum ReduceMax ReduceMin ReduceProd ReduceL1 ReduceL2
ReduceLogSum ReduceLogSumExp ReduceSumSquare ArgMax ArgMin""".split())
POOL = frozenset(("MaxPool", "AveragePool", "LpPool"))
GLOBAL_POOL = frozenset(("GlobalAveragePool", "GlobalMaxPool", "GlobalLpPool"))
RESAMPLE = frozenset(("Resize", "Upsample"))
ZERO = frozenset("""Reshape Flatten Transpose Squeeze Unsqueeze Concat Split Slice Gather
GatherElements GatherND Identity Cast CastLike Shape Size Constant ConstantOfShape Dropout Pad
Expand Tile DepthToSpace SpaceToDepth QuantizeLinear DequantizeLinear NonZero Range
""".split())

_PARAM_TYPES = None  # filled lazily: onnx TensorProto float/8-bit types


@dataclass
class MacReport:
    """MACs and parameters of one inference, with a per-operator breakdown."""

    macs: int
    params: int
    by_op: dict = field(default_factory=dict)       # op_type -> MACs
    uncounted: list = field(default_factory=list)   # "op_type node_name: why"

    def to_dict(self) -> dict:
        """The fields as a JSON-ready dict."""
        return {"macs": self.macs, "params": self.params, "by_op": dict(self.by_op),
                "uncounted": list(self.uncounted)}


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


def _prod(xs) -> int:
    n = 1
    for x in xs:
        n *= int(x)
    return n


def _dims(type_proto):
    """Shape of a tensor type as a list of int or None (unknown); None if no shape."""
    t = type_proto.tensor_type
    if not t.HasField("shape"):
        return None
    out = []
    for d in t.shape.dim:
        out.append(d.dim_value if d.HasField("dim_value") and d.dim_value > 0 else None)
    return out


def fix_input_shapes(model, shapes: dict | None = None):
    """A copy of ``model`` whose graph inputs have concrete dims.

    ``shapes`` maps input name -> full shape; otherwise unknown dims become 1
    (batch) and anything else unknown stays unknown.
    """
    m = onnx.ModelProto()
    m.CopyFrom(model)
    inits = {i.name for i in m.graph.initializer}
    for inp in m.graph.input:
        if inp.name in inits:
            continue
        dims = inp.type.tensor_type.shape.dim
        want = (shapes or {}).get(inp.name)
        if want is not None:
            if len(want) != len(dims):
                raise ConfigError(f"input {inp.name!r}: shape {tuple(want)} has rank {len(want)}; "
                                  f"the model's input has rank {len(dims)}")
            for d, v in zip(dims, want):
                d.ClearField("dim_param")
                d.dim_value = int(v)
        elif len(dims) and not (dims[0].HasField("dim_value") and dims[0].dim_value > 0):
            dims[0].ClearField("dim_param")
            dims[0].dim_value = 1
    return m


def _param_count(model) -> int:
    TensorProto = onnx.TensorProto
    kinds = {TensorProto.FLOAT, TensorProto.FLOAT16, TensorProto.DOUBLE, TensorProto.BFLOAT16,
             TensorProto.INT8, TensorProto.UINT8}
    n = 0
    for t in model.graph.initializer:
        if t.data_type in kinds:
            n += _prod(t.dims)
    for node in model.graph.node:
        if node.op_type == "Constant":
            for a in node.attribute:
                if a.name == "value" and a.t.data_type in kinds:
                    n += _prod(a.t.dims)
    return n


def count_macs(model, input_shapes: dict | None = None) -> MacReport:
    """MACs per inference and parameter count of an ONNX model (ModelProto or path).

    ``input_shapes``: {input name: full shape} for inputs with dynamic dims.
    """
    if not isinstance(model, onnx.ModelProto):
        model = load_onnx(model)
    g, shape, shape_error = _inferred_shapes(fix_input_shapes(model, input_shapes))
    total = 0
    by_op: dict[str, int] = {}
    uncounted: list[str] = []
    for node in g.node:
        label = f"{node.op_type} {node.name or node.output[0]}"
        if node.domain not in ("", "ai.onnx"):
            uncounted.append(f"{label}: custom domain {node.domain!r}")
            continue
        macs = _node_macs(node, shape)
        if macs is _UNKNOWN_OP:
            uncounted.append(f"{label}: operator not counted (0 MACs)")
        elif macs is None:
            uncounted.append(f"{label}: {shape_error or 'shapes unknown after shape inference'}")
        elif macs:
            total += macs
            by_op[node.op_type] = by_op.get(node.op_type, 0) + macs
    return MacReport(macs=int(total), params=_param_count(model), by_op=by_op, uncounted=uncounted)


_UNKNOWN_OP = object()


def _inferred_shapes(fixed):
    """(graph, shape(name) -> list or None, shape-inference error or None)."""
    try:
        inferred = onnx.shape_inference.infer_shapes(fixed, strict_mode=False, data_prop=True)
        shape_error = None
    except Exception as e:  # inconsistent graph: fall back to declared shapes
        inferred = fixed
        shape_error = f"shape inference failed: {type(e).__name__}: {e}"
    g = inferred.graph
    shapes: dict[str, list | None] = {}
    for vi in list(g.input) + list(g.value_info) + list(g.output):
        shapes[vi.name] = _dims(vi.type)
    for t in g.initializer:
        shapes[t.name] = [int(d) for d in t.dims]
    for node in g.node:
        if node.op_type == "Constant":
            for a in node.attribute:
                if a.name == "value":
                    shapes[node.output[0]] = [int(d) for d in a.t.dims]

    def shape(name):
        s = shapes.get(name)
        if s is None or any(d is None for d in s):
            return None
        return s
    return g, shape, shape_error


def _node_macs(node, shape):
    """MACs of one node; None when its shapes are unknown, _UNKNOWN_OP for an uncounted op."""
    op = node.op_type
    attrs = {a.name: onnx.helper.get_attribute_value(a) for a in node.attribute}
    out = shape(node.output[0]) if node.output else None
    x = shape(node.input[0]) if node.input else None
    if op in ZERO:
        return 0
    if op == "Conv":
        w = shape(node.input[1])
        return _prod(out) * _prod(w[1:]) if out is not None and w is not None else None
    if op == "ConvTranspose":
        w = shape(node.input[1])
        return _prod(x) * _prod(w[1:]) if x is not None and w is not None else None
    if op == "Gemm":
        if x is not None and out is not None and len(x) == 2:
            return _prod(out) * (x[0] if attrs.get("transA", 0) else x[1])
        return None
    if op == "MatMul":
        return max(1, _prod(out)) * x[-1] if x is not None and out is not None else None
    if op in POOL:
        ks = attrs.get("kernel_shape")
        return _prod(out) * _prod(ks) if out is not None and ks else None
    if op in GLOBAL_POOL or op in REDUCE:
        return _prod(x) if x is not None else None
    if op in ELEMENTWISE or op in RESAMPLE:
        return _prod(out) if out is not None else None
    return _UNKNOWN_OP


__all__ = ["MacReport", "count_macs", "fix_input_shapes", "load_onnx"]
