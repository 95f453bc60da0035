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
Not And Or Xor Mod IsNaN IsInf Hardmax Shrink BitShift Swish CumSum MeanVarianceNormalization
LpNormalization RMSNormalization RotaryEmbedding SkipSimplifiedLayerNormalization Det Bernoulli
RandomNormalLike RandomUniformLike BitwiseAnd BitwiseOr BitwiseXor BitwiseNot Acos Asin Atan
Acosh Asinh Atanh Cosh Sinh Tan AffineGrid CumProd SwiGLU RandomNormal RandomUniform Multinomial
HannWindow HammingWindow BlackmanWindow NegativeLogLikelihoodLoss SoftmaxCrossEntropyLoss MaxRoiPool
""".split())
REDUCE = frozenset("""ReduceMean ReduceSum ReduceMax ReduceMin ReduceProd ReduceL1 ReduceL2
ReduceLogSum ReduceLogSumExp ReduceSumSquare ArgMax ArgMin TopK""".split())
POOL = frozenset(("MaxPool", "AveragePool", "LpPool"))
GLOBAL_POOL = frozenset(("GlobalAveragePool", "GlobalMaxPool", "GlobalLpPool"))
RESAMPLE = frozenset(("Resize", "Upsample", "GridSample", "RoiAlign"))
CONV = frozenset(("Conv", "ConvInteger", "QLinearConv", "ConvTranspose", "DeformConv"))
MATMUL = frozenset(("Gemm", "MatMul", "MatMulInteger", "QLinearMatMul"))
ZERO = frozenset("""Reshape Flatten Transpose Squeeze Unsqueeze Concat Split Slice Gather
GatherElements GatherND Identity Cast CastLike Shape Size Constant ConstantOfShape Dropout Pad
Expand Tile DepthToSpace SpaceToDepth QuantizeLinear DequantizeLinear DynamicQuantizeLinear
NonZero Range ScatterND ScatterElements Scatter OneHot Trilu Compress NonMaxSuppression
EyeLike ReverseSequence MaxUnpool CenterCropPad Col2Im Unique SequenceConstruct SequenceAt
SequenceInsert SequenceErase SequenceEmpty SequenceLength SplitToSequence ConcatFromSequence
Optional OptionalGetElement OptionalHasElement BitCast TensorScatter MelWeightMatrix""".split())
ACTIVATIONS = frozenset("""Relu Clip LeakyRelu Sigmoid HardSigmoid HardSwish Tanh Elu Selu
Softplus""".split())
#: standard operators left uncounted on purpose (a graph holding one is refused by name, or
#: counted as 0 with ``allow_uncounted``): control flow whose cost depends on the data (If,
#: Loop, Scan, SequenceMap), transforms whose cost is not out-elements (DFT, STFT), text and
#: image decoding, and the newest stateful layers (LinearAttention, CausalConvWithState)
NOT_COUNTED = frozenset("""If Loop Scan SequenceMap DFT STFT ImageDecoder RegexFullMatch
StringConcat StringNormalizer StringSplit TfIdfVectorizer LinearAttention
CausalConvWithState""".split())
#: recurrent layers (ONNX LSTM, GRU, RNN): every time step multiplies the input by W and the
#: hidden state by R, so seq * batch * (elements of W + elements of R) MACs (W: [directions,
#: gates * hidden, input], R: [directions, gates * hidden, hidden]; the gates' element-wise
#: work is left out, as a bias is for Gemm)
RECURRENT = frozenset(("LSTM", "GRU", "RNN"))
#: ONNX Runtime's contrib operators (domain ``com.microsoft``) that its quantizer
#: (QOperator format) and graph optimizers write, and the standard operator each is counted
#: as: their data inputs sit where the standard operator's do (ONNX Runtime "Contrib
#: operators" reference, ``docs/ContribOperators.md``)
MS_OPS = {
    "QLinearAdd": "Add", "QLinearMul": "Mul", "QLinearSigmoid": "Sigmoid",
    "QLinearLeakyRelu": "LeakyRelu", "QLinearSoftmax": "Softmax", "QLinearConcat": "Concat",
    "QLinearWhere": "Where", "QLinearGlobalAveragePool": "GlobalAveragePool",
    "QLinearAveragePool": "AveragePool", "QGemm": "Gemm", "FusedConv": "Conv",
    "FusedMatMul": "MatMul", "MatMulIntegerToFloat": "MatMul", "DynamicQuantizeMatMul": "MatMul",
    "Gelu": "Gelu", "FastGelu": "Gelu", "BiasGelu": "Gelu", "QuickGelu": "Gelu",
    "BiasAdd": "Add", "SkipLayerNormalization": "LayerNormalization",
    "QuantizeLinear": "QuantizeLinear", "DequantizeLinear": "DequantizeLinear",
    "NhwcMaxPool": "MaxPool", "DynamicQuantizeLSTM": "LSTM",
}
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
    if node.domain == "com.microsoft" and op in MS_OPS:
        op = MS_OPS[op]                  # counted as the standard operator it stands for
    elif node.domain not in ("", "ai.onnx"):
        return "data", 0, f"custom domain {node.domain!r}"

    def s(i, outs=False):
        return _shape(shapes, node.output if outs else node.input, i)
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
    elif op in RECURRENT or op in ("Einsum", "Attention"):
        kind = "matmul"
        need, macs = _matmul_like(op, node, shapes, attrs)
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


def _shape(shapes, names, i):
    return shapes.get(names[i]) if len(names) > i and names[i] else None


def _matmul_like(op, node, shapes, attrs) -> tuple[object, int]:
    """(a known shape or None, MACs) of a recurrent layer, an Einsum or an Attention."""
    x = _shape(shapes, node.input, 0)
    if op in RECURRENT:
        w, r = _shape(shapes, node.input, 1), _shape(shapes, node.input, 2)
        if x is None or w is None or r is None or len(x) != 3:
            return None, 0
        seq, batch = (x[1], x[0]) if attrs.get("layout", 0) else (x[0], x[1])
        return x, seq * batch * (math.prod(w) + math.prod(r))
    if op == "Einsum":
        return _einsum(attrs.get("equation", b""), node, shapes)
    # Attention (opset 23): softmax(Q K^T) V, so kv_seq * (Q elements + output elements)
    k, out = _shape(shapes, node.input, 1), _shape(shapes, node.output, 0)
    if x is None or k is None or out is None or len(k) not in (3, 4):
        return None, 0
    kv_seq = k[-2] if len(k) == 4 else k[1]
    return out, kv_seq * (math.prod(x) + math.prod(out))


def _einsum(equation, node, shapes) -> tuple[object, int]:
    """MACs of an Einsum: output elements * the product of the summed labels' sizes."""
    eq = (equation.decode() if isinstance(equation, bytes) else str(equation)).replace(" ", "")
    lhs, arrow, rhs = eq.partition("->")
    terms = lhs.split(",")
    ins = [_shape(shapes, node.input, i) for i in range(len(terms))]
    if any(s is None for s in ins) or len(terms) != len(node.input):
        return None, 0
    size: dict[str, int] = {}
    for term, shp in zip(terms, ins):
        head, ell, tail = term.partition("...")
        if len(head) + len(tail) > len(shp) or (not ell and len(term) != len(shp)):
            return None, 0
        named = tuple(shp[:len(head)]) + (tuple(shp[len(shp) - len(tail):]) if tail else ())
        for c, d in zip(head + tail, named):
            size[c] = max(size.get(c, 1), int(d))
    kept = set(rhs) if arrow else {c for c in size if lhs.count(c) == 1}  # implicit output
    out = _shape(shapes, node.output, 0)
    if out is None:
        return None, 0
    summed = math.prod(d for c, d in size.items() if c not in kept)
    return out, max(1, math.prod(out)) * summed


__all__ = ["ACTIVATIONS", "CONV", "MS_OPS", "NOT_COUNTED", "RECURRENT", "ELEMENTWISE", "GLOBAL_POOL", "MATMUL", "POOL", "REDUCE", "RESAMPLE", "ZERO",
           "is_folded", "node_cost", "weight_names"]
