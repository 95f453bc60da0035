"""What one inference of an ONNX network costs, node by node.

``analyze(model, input_shape=None)`` gives a ``NetworkCost``: per node its MACs, the
elements it reads and writes, its weights, its class (``kind``) and the node it is
fused into the way runtimes fuse. Shapes come from the whole graph (``_shapes``:
ONNX shape inference with data propagation, then one ONNX Runtime run for the rest).
A node whose cost cannot be counted (unknown operator, custom domain, a shape no
engine could read) is a ``ConfigError`` naming it; ``allow_uncounted=True`` turns that
into a warning giving the uncounted share.

=====================  ========== =====================================================
operator               kind       MACs
=====================  ========== =====================================================
Conv (group 1),        conv       out_elements * (C_in / group) * prod(kernel);
ConvTranspose                     ConvTranspose: in_elements * (C_out / group) * k
Conv (group > 1)       dwconv     the same formula (depthwise and grouped)
Gemm, MatMul           matmul     M * N * K (batched per numpy rules); bias not counted
LSTM, GRU, RNN         matmul     seq * batch * (elements of W + elements of R)
Einsum                 matmul     out_elements * prod(sizes of the summed labels)
Attention (opset 23)   matmul     kv_seq * (Q elements + output elements)
Max/Average/LpPool     pool       out_elements * prod(kernel_shape)
Global*Pool            pool       in_elements
element-wise, norms,   elementwise out_elements (Resize, activations, BatchNorm...);
Reduce*, TopK                     Reduce*, ArgMax, TopK: in_elements
data movement          data       0: Reshape Transpose Concat Split Slice Gather Cast ...
=====================  ========== =====================================================

ONNX Runtime's contrib operators (``com.microsoft``: FusedConv, QGemm, QLinearAdd, ...)
count as the standard operator they stand for (``_ops.MS_OPS``).

Fusion (``fused_into``, the name of the node that absorbs it; ``_fusion``): a Conv or
ConvTranspose absorbs a following BatchNormalization, then one activation (Relu,
Clip, LeakyRelu, Sigmoid, HardSigmoid, HardSwish, Tanh, Elu, Selu, Softplus, or
SiLU / hard-swish written as ``x * Sigmoid(x)`` / ``x * HardSigmoid(x)``); a MatMul
absorbs a bias ``Add`` and then an activation; each link only when the tensor has
that one consumer and is not a graph output. Nodes computed from constants only
(shape arithmetic, ``Constant``, ``Shape`` of a static tensor) carry
``fused_into = FOLDED``, kind ``data`` and 0 MACs: runtimes fold them when they load
the model. In a quantized graph's QDQ format, the activations' Quantize/DequantizeLinear
nodes are absorbed into the layer they wrap, and ``meta["int8"]`` says how the graph is
quantized (``_fusion.quantization``).
"""

from __future__ import annotations

import csv
import io
import math
import os
import warnings
from dataclasses import dataclass, field, replace

import onnx

from .._io import atomic_write
from ..errors import ConfigError
from ._fusion import FOLDED, QOPERATOR, fuse, fuse_patterns, fuse_qdq, half_weights, quantization
from ._ops import is_folded, node_cost, weight_names
from ._shapes import (
    constant_shapes,
    fix_input_shapes,
    graph_inputs,
    infer_shapes,
    load_onnx,
    static_shape,
)

KINDS = ("conv", "dwconv", "matmul", "elementwise", "pool", "data")
CSV_FIELDS = ("name", "op_type", "kind", "macs", "weight_elems", "in_elems", "out_elems",
              "fused_into")
CSV_SCHEMA = "flockai-network-cost/1"

class DynamicInputError(ConfigError):
    """An input with open dims and no ``input_shape`` for it (``input_name``, ``dims``: '?'
    where open), so that a caller can say how to give the shape in its own terms."""

    def __init__(self, message: str, input_name: str, dims: list):
        super().__init__(message)
        self.input_name, self.dims = input_name, dims


@dataclass(frozen=True)
class NodeCost:
    """Cost of one node of one inference (elements, not bytes: the precision decides)."""

    name: str
    op_type: str
    kind: str
    macs: int
    weight_elems: int
    in_elems: int
    out_elems: int
    fused_into: str | None = None
    #: a layer a quantized graph's runtime computes in float (``ort_graph``: one ONNX
    #: Runtime did not fuse into an int8 operator); it runs at fp32 on an int8 deployment
    in_float: bool = False


@dataclass(frozen=True)
class NetworkCost:
    """Per-node costs of one inference of a network, with totals."""

    nodes: tuple[NodeCost, ...]
    name: str = ""
    input_shape: tuple[int, ...] | None = None
    uncounted: tuple[str, ...] = ()
    meta: dict = field(default_factory=dict, compare=False, repr=False)

    @property
    def macs(self) -> int:
        return sum(n.macs for n in self.nodes)

    @property
    def weight_elems(self) -> int:
        return sum(n.weight_elems for n in self.nodes)

    @property
    def in_elems(self) -> int:
        return sum(n.in_elems for n in self.nodes)

    @property
    def out_elems(self) -> int:
        return sum(n.out_elems for n in self.nodes)

    @property
    def run_nodes(self) -> tuple[NodeCost, ...]:
        """The nodes a runtime dispatches: neither folded nor fused into another."""
        return tuple(n for n in self.nodes if n.fused_into is None)

    def by_kind(self) -> dict[str, int]:
        """MACs per kind (every kind present, 0 when none)."""
        out = dict.fromkeys(KINDS, 0)
        for n in self.nodes:
            out[n.kind] += n.macs
        return out

    def by_op(self) -> dict[str, int]:
        """MACs per operator type (types with MACs > 0)."""
        out: dict[str, int] = {}
        for n in self.nodes:
            if n.macs:
                out[n.op_type] = out.get(n.op_type, 0) + n.macs
        return out

    def to_csv(self, path=None) -> str:
        """The costs as CSV text (``# key=value`` header lines, then one row per node);
        written atomically to ``path`` when given."""
        buf = io.StringIO()
        buf.write(f"# schema={CSV_SCHEMA}\n# name={self.name}\n")
        if self.input_shape is not None:
            buf.write(f"# input_shape={'x'.join(str(d) for d in self.input_shape)}\n")
        for k, v in self.meta.items():
            if not k.startswith("_"):           # "_graph": the model itself, not written
                buf.write(f"# {k}={str(v).replace(chr(10), ' ')}\n")
        for u in self.uncounted:
            buf.write(f"# uncounted={u}\n")
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(CSV_FIELDS)
        for n in self.nodes:
            w.writerow((n.name, n.op_type, n.kind, n.macs, n.weight_elems, n.in_elems,
                        n.out_elems, "" if n.fused_into is None else n.fused_into))
        text = buf.getvalue()
        if path is not None:
            atomic_write(path, lambda fh: fh.write(text))
        return text

    @classmethod
    def from_csv(cls, source) -> NetworkCost:
        """Read ``to_csv`` output: a path or the CSV text itself."""
        where = "network cost CSV"
        if isinstance(source, os.PathLike) or (isinstance(source, str) and "\n" not in source):
            where = f"network cost CSV {os.fspath(source)!r}"
            try:
                with open(source, encoding="utf-8") as fh:
                    source = fh.read()
            except OSError as e:
                raise ConfigError(f"{where}: cannot be read ({e})") from None
        head: dict[str, str] = {}
        uncounted: list[str] = []
        body = []
        for line in str(source).splitlines():
            if line.startswith("#"):
                k, _, v = line[1:].strip().partition("=")
                if k == "uncounted":
                    uncounted.append(v)
                else:
                    head[k] = v
            elif line.strip():
                body.append(line)
        if head.get("schema") != CSV_SCHEMA:
            raise ConfigError(f"{where}: schema = {head.get('schema')!r} is not allowed; "
                              f"expected {CSV_SCHEMA!r}")
        rows = list(csv.reader(body))
        if not rows or tuple(rows[0]) != CSV_FIELDS:
            raise ConfigError(f"{where}: header = {rows[0] if rows else None!r}; expected "
                              f"{list(CSV_FIELDS)}")
        nodes = []
        for i, r in enumerate(rows[1:], start=2):
            try:
                if len(r) != len(CSV_FIELDS) or r[2] not in KINDS:
                    raise ValueError(r)
                nums = [int(x) for x in r[3:7]]
                if min(nums) < 0:
                    raise ValueError(r)
            except ValueError:
                raise ConfigError(f"{where}: row {i} = {r!r} is not allowed; expected "
                                  f"{list(CSV_FIELDS)} with kind in {list(KINDS)} and "
                                  f"counts >= 0") from None
            nodes.append(NodeCost(r[0], r[1], r[2], nums[0], nums[1], nums[2], nums[3], r[7] or None))
        name = head.pop("name", "")
        shape = head.pop("input_shape", "")
        head.pop("schema")
        return cls(tuple(nodes), name, tuple(int(d) for d in shape.split("x")) if shape else None,
                   tuple(uncounted), head)


def _proto_and_shapes(model, input_shape):
    """(ModelProto, {input name: shape} or None, default name) from what analyze takes."""
    name = ""
    if isinstance(model, onnx.ModelProto):
        proto = model
    elif isinstance(model, (bytes, bytearray)):
        try:
            proto = onnx.load_from_string(bytes(model))
        except Exception as e:
            raise ConfigError(f"model = <{len(model)} bytes> is not a valid ONNX model: "
                              f"{type(e).__name__}: {e}") from None
    elif isinstance(model, (str, os.PathLike)):
        proto = load_onnx(model)
        name = os.path.splitext(os.path.basename(os.fspath(model)))[0]
    elif hasattr(model, "session") and isinstance(getattr(model, "path", None), str):
        proto = getattr(model, "_proto", None) or load_onnx(model.path)  # an OnnxModel
        name = getattr(model, "name", "") or ""
        if input_shape is None and getattr(model, "input_size", None) is not None:
            h, w = model.input_size
            c = model.channels
            input_shape = (1, c, h, w) if model.layout == "NCHW" else (1, h, w, c)
    else:
        raise ConfigError(f"model = {model!r} is not allowed; expected an ONNX path, bytes, "
                          f"an onnx.ModelProto or an OnnxModel")
    return proto, _input_shapes(proto, input_shape), name or proto.graph.name


def _input_shapes(proto, input_shape):
    if input_shape is None or isinstance(input_shape, dict):
        return input_shape
    inputs = graph_inputs(proto)
    if not inputs:
        raise ConfigError(f"input_shape = {input_shape!r}: the model has no inputs to shape")
    first = inputs[0]
    dims = [d.dim_value if d.HasField("dim_value") and d.dim_value > 0 else None
            for d in first.type.tensor_type.shape.dim]
    if isinstance(input_shape, (int,)) and not isinstance(input_shape, bool):
        side = int(input_shape)
        if len(dims) != 4 or side < 1:
            raise ConfigError(f"input_shape = {input_shape!r} is not allowed for input "
                              f"{first.name!r} of rank {len(dims)}; give the full shape")
        if dims[1] in (1, 3, 4) or dims[3] not in (1, 3, 4):
            return {first.name: (1, dims[1] or 3, side, side)}
        return {first.name: (1, side, side, dims[3])}
    try:
        return {first.name: tuple(int(d) for d in input_shape)}
    except (TypeError, ValueError):
        raise ConfigError(f"input_shape = {input_shape!r} is not allowed; expected a side "
                          f"(int), a full shape or {{input name: shape}}") from None


def analyze(model, input_shape=None, *, allow_uncounted: bool = False,
            name: str | None = None, as_run: bool = False) -> NetworkCost:
    """Per-node costs of one inference of ``model`` (ONNX path, bytes, ModelProto or
    OnnxModel). ``input_shape``: the first input's full shape, its square side (an int,
    batch 1), or ``{input name: shape}``; dynamic batch dims default to 1. ``as_run``: the
    graph a runtime's optimizer wrote (``ort_graph``): its Q/DQ nodes are passes of their
    own, and a float layer in it is marked ``in_float``. A QDQ graph keeps its
    shape-fixed proto in ``meta["_graph"]`` (not written by ``to_csv``)."""
    proto, shapes_in, default_name = _proto_and_shapes(model, input_shape)
    fixed = fix_input_shapes(proto, shapes_in)
    for inp in graph_inputs(fixed):
        if static_shape(inp.type) is None:
            dims = [d.dim_value if d.HasField("dim_value") and d.dim_value > 0
                    else d.dim_param or "?" for d in inp.type.tensor_type.shape.dim]
            raise DynamicInputError(
                f"input_shape = {input_shape!r}: input {inp.name!r} of "
                f"{default_name or 'the model'!r} has dims {dims}; give its full shape (e.g. "
                f"input_shape={{{inp.name!r}: (1, 3, 480, 640)}})", inp.name, dims)
    shapes, how, error = infer_shapes(fixed)
    consts = set(constant_shapes(fixed))
    weights = weight_names(fixed)
    g = fixed.graph
    nodes: list[NodeCost] = []
    uncounted: list[str] = []
    seen: set[str] = set()
    for i, node in enumerate(g.node):
        label = node.name or node.output[0] or f"#{i}"
        if label in seen:                # node names are not required to be unique
            label = f"{label}#{i}"
        seen.add(label)
        is_const = is_folded(node, consts, shapes)
        if is_const:
            consts.update(o for o in node.output if o)
            if node.op_type not in ("Shape", "Size") and any(i in weights for i in node.input):
                weights.update(o for o in node.output if o)     # e.g. Identity(weight)
        kind, macs, why = node_cost(node, shapes)
        if is_const:                     # computed once when the runtime loads the model
            kind, macs = "data", 0
        elif why is not None:
            uncounted.append(f"{node.op_type} {label}: {why}")
            kind, macs = "data", 0

        def elems(names, *, weight=False):
            return sum(math.prod(shapes[n]) for n in names
                       if n and n in shapes and ((n in weights) == weight))
        nodes.append(NodeCost(label, node.op_type, kind, int(macs), elems(node.input, weight=True),
                              elems(node.input), elems(node.output),
                              FOLDED if is_const else None))
    nodes = fuse_patterns(g, fuse(g, nodes))
    if as_run:
        nodes = [replace(n, in_float=True) if n.kind in ("conv", "dwconv", "matmul")
                 and n.op_type not in QOPERATOR and n.fused_into is None else n for n in nodes]
    else:
        nodes = fuse_qdq(g, nodes)
    shape = next(iter(shapes.get(i.name) for i in graph_inputs(fixed)), None)
    meta: dict = {"shapes": how}
    quant = quantization(g)
    if quant:
        meta["int8"] = quant
        if quant == "qdq" and not as_run:
            meta["_graph"] = fixed
    elif half_weights(g):
        meta["fp16"] = True
    cost = NetworkCost(tuple(nodes), name or default_name, shape, tuple(uncounted), meta)
    if uncounted:
        _refuse_or_warn(cost, error, allow_uncounted)
    return cost


def _refuse_or_warn(cost: NetworkCost, error, allow: bool) -> None:
    n_run = sum(1 for n in cost.nodes if n.fused_into != FOLDED)
    share = len(cost.uncounted) / max(1, n_run)
    shown = "; ".join(cost.uncounted[:8]) + (f"; ... {len(cost.uncounted) - 8} more"
                                             if len(cost.uncounted) > 8 else "")
    text = (f"{len(cost.uncounted)} of {n_run} nodes of {cost.name or 'the model'!r} "
            f"({share:.1%}) are not counted: {shown}" + (f" ({error})" if error else ""))
    if error and any("shapes unknown" in u for u in cost.uncounted) and not any(
            "custom domain" in u for u in cost.uncounted):
        # the shapes are unknown because the model does not run (not for an operator of
        # another domain, named first as it is): say that first
        text = (f"{cost.name or 'the model'!r} does not run in ONNX Runtime, so the shapes of "
                f"{len(cost.uncounted)} of its {n_run} nodes are unknown ({error}); first "
                f"nodes: {shown}")
    if not allow:
        raise ConfigError(f"{text}. Its cost would be under-counted; pass allow_uncounted=True "
                          f"to count them as 0 with a warning, or state the MACs yourself "
                          f"(e.g. OnnxModel(..., macs=N))")
    warnings.warn(f"pytest-flockai: {text}; counted as 0 (allow_uncounted=True)", stacklevel=3)


__all__ = ["FOLDED", "KINDS", "DynamicInputError", "NetworkCost", "NodeCost", "analyze",
           "quantization"]
