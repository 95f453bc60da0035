"""Operator tables and per-node MAC rules behind ``graph.analyze`` (the table in
``graph``'s docstring)."""

from __future__ import annotations

import math

import onnx

ELEMENTWISE = frozenset("""
Add Sub Mul Div Pow Sqrt Exp Log Abs Neg Reciprocal Floor Ceil Round Sign Max Min Sum Mean
Relu LeakyRelu PRelu Elu Selu Celu ThresholdedRelu Sigmoid HardSigmoid HardSwish Tanh Softplus
Softsign Clip Erf Gelu Mish Sin Cos Softmax LogSoftmax BatchNormalization InstanceNormalization
LayerNormalization GroupNormalization LRN Where Equal Greater GreaterOrEqual Less LessOrEqual
Not And Or Xor Mod IsNaN IsInf Hardmax Shrink BitShift Swish
""".split())
REDUCE = frozenset("""ReduceMean ReduceSum ReduceMax ReduceMin ReduceProd ReduceL1 ReduceL2
ReduceLogSum ReduceLogSumExp ReduceSumSquare ArgMax ArgMin TopK""".split())
POOL = frozenset(("MaxPool", "AveragePool", "LpPool"))
GLOBAL_POOL = frozenset(("GlobalAveragePool", "GlobalMaxPool", "GlobalLpPool"))
RESAMPLE = frozenset(("Resize", "Upsample", "GridSample", "RoiAlign"))
CONV = frozenset(("Conv", "ConvInteger", "QLinearConv", "ConvTranspose"))
MATMUL = frozenset(("Gemm", "MatMul", "MatMulInteger", "QLinearMatMul"))
ZERO = frozenset("""Reshape Flatten Transpose Squeeze Unsqueeze Concat Split Slice Gather
GatherElements GatherND Identity Cast CastLike Shape Size Constant ConstantOfShape Dropout Pad
Expand Tile DepthToSpace SpaceToDepth QuantizeLinear DequantizeLinear DynamicQuantizeLinear
NonZero Range ScatterND ScatterElements Scatter OneHot Trilu Compress NonMaxSuppression
EyeLike ReverseSequence""".split())
ACTIVATIONS = frozenset("""Relu Clip LeakyRelu Sigmoid HardSigmoid HardSwish Tanh Elu Selu
Softplus""".split())
_WEIGHT_TYPES = frozenset((onnx.TensorProto.FLOAT, onnx.TensorProto.FLOAT16,
                           onnx.TensorProto.DOUBLE, onnx.TensorProto.BFLOAT16,
                           onnx.TensorProto.INT8, onnx.TensorProto.UINT8))


def weight_names(m: onnx.ModelProto) -> set[str]:
    out = {t.name for t in m.graph.initializer if t.data_type in _WEIGHT_TYPES}
    for node in m.graph.node:
        if node.op_type == "Constant":
            for a in node.attribute:
                if a.name == "value" and a.t.data_type in _WEIGHT_TYPES:
                    out.add(node.output[0])
    return out


def is_folded(node, consts: set[str], shapes: dict) -> bool:
    if node.op_type == "Constant":
        return True
    if node.op_type in ("Shape", "Size"):
        return bool(node.input) and node.input[0] in shapes
    ins = [i for i in node.input if i]
    return bool(ins) and all(i in consts for i in ins) and node.op_type not in (
        "RandomNormal", "RandomUniform", "RandomNormalLike", "RandomUniformLike", "Multinomial")


def node_cost(node, shapes) -> tuple[str, int, str | None]:
    """(kind, MACs, None) or (kind, 0, why it cannot be counted)."""
    op = node.op_type
    if node.domain not in ("", "ai.onnx"):
        return "data", 0, f"custom domain {node.domain!r}"

    def s(i, outs=False):
        names = node.output if outs else node.input
        return shapes.get(names[i]) if len(names) > i and names[i] else None
    out, x = s(0, True), s(0)
    if op in ZERO:
        return "data", 0, None
    attrs = {a.name: onnx.helper.get_attribute_value(a) for a in node.attribute}
    need = out
    macs = 0
    kind = "elementwise"
    if op in CONV:
        w = s(3) if op == "QLinearConv" else s(1)
        kind = "dwconv" if int(attrs.get("group", 1)) > 1 else "conv"
        if op == "ConvTranspose":
            need = None if x is None or w is None else x
            macs = math.prod(x) * math.prod(w[1:]) if need else 0
        else:
            need = None if out is None or w is None else out
            macs = math.prod(out) * math.prod(w[1:]) if need else 0
    elif op in MATMUL:
        kind = "matmul"
        if op == "Gemm":
            need = out if x is not None and out is not None and len(x) == 2 else None
            macs = math.prod(out) * (x[0] if attrs.get("transA", 0) else x[1]) if need else 0
        else:
            need = out if x is not None and out is not None else None
            macs = max(1, math.prod(out)) * x[-1] if need else 0
    elif op in POOL:
        kind = "pool"
        ks = attrs.get("kernel_shape")
        macs = math.prod(out) * math.prod(ks) if out is not None and ks else 0
        need = out if ks else None
    elif op in GLOBAL_POOL or op in REDUCE:
        kind = "pool" if op in GLOBAL_POOL else "elementwise"
        need = x
        macs = math.prod(x) if x is not None else 0
    elif op in ELEMENTWISE or op in RESAMPLE:
        macs = math.prod(out) if out is not None else 0
    else:
        return "data", 0, "operator not counted"
    if need is None:
        return kind, 0, "shapes unknown after shape inference and an onnxruntime run"
    return kind, int(macs), None


__all__ = ["ACTIVATIONS", "CONV", "ELEMENTWISE", "GLOBAL_POOL", "MATMUL", "POOL", "REDUCE", "RESAMPLE", "ZERO",
           "is_folded", "node_cost", "weight_names"]
