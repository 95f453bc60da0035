"""Per-node costs of an ONNX graph for the latency model, when ``compute.graph`` is absent.

A stand-in for ``compute.graph.analyze`` (same NodeCost fields) built on ``ml.macs``'s
shape inference; ``analyze`` below prefers ``compute.graph`` whenever it is installed.
"""

from __future__ import annotations

from dataclasses import dataclass

import onnx

from ..ml import macs as _m


@dataclass(frozen=True)
class NodeCost:
    name: str
    op_type: str
    kind: str
    macs: float
    weight_elems: float
    in_elems: float
    out_elems: float
    fused_into: str | None = None


@dataclass(frozen=True)
class NetworkCost:
    nodes: tuple
    name: str = ""

    @property
    def macs(self) -> float:
        return float(sum(n.macs for n in self.nodes))


_FUSABLE = frozenset("BatchNormalization Relu Clip LeakyRelu Sigmoid HardSwish HardSigmoid Mul "
                     "Add Silu".split())


def _kind(node, attrs) -> str:
    op = node.op_type
    if op in ("Conv", "ConvTranspose"):
        return "dwconv" if int(attrs.get("group", 1)) > 1 else "conv"
    if op in ("Gemm", "MatMul"):
        return "matmul"
    if op in _m.POOL or op in _m.GLOBAL_POOL or op in _m.REDUCE:
        return "pool"
    if op in _m.ELEMENTWISE or op in _m.RESAMPLE:
        return "elementwise"
    return "data"


def analyze(model, input_shape=None) -> NetworkCost:
    """Per-node costs (see the module docstring)."""
    if not isinstance(model, onnx.ModelProto):
        model = onnx.load_from_string(model) if isinstance(model, bytes) else _m.load_onnx(model)
    inputs = None
    inits = {t.name for t in model.graph.initializer}
    real = [i for i in model.graph.input if i.name not in inits]
    if input_shape is not None and real:
        inputs = {real[0].name: list(input_shape)}
    g, shape, _err = _m._inferred_shapes(_m.fix_input_shapes(model, inputs))
    wsize = {t.name: _m._prod(t.dims) for t in g.initializer}
    consumers: dict[str, int] = {}
    for node in g.node:
        for i in node.input:
            consumers[i] = consumers.get(i, 0) + 1
    producer_fused: dict[str, str] = {}         # tensor -> the conv it belongs to
    nodes = []
    for node in g.node:
        attrs = {a.name: onnx.helper.get_attribute_value(a) for a in node.attribute}
        macs = _m._node_macs(node, shape)
        macs = 0 if macs is None or macs is _m._UNKNOWN_OP else macs
        name = node.name or node.output[0]
        w = sum(wsize.get(i, 0) for i in node.input)
        act = [shape(i) for i in node.input if i and i not in wsize]
        ins = sum(_m._prod(s) for s in act if s is not None)
        out = sum(_m._prod(s) for s in (shape(o) for o in node.output) if s is not None)
        kind = _kind(node, attrs)
        fused = None
        src = node.input[0] if node.input else ""
        if (node.op_type in _FUSABLE and src in producer_fused and consumers.get(src, 0) <= 2):
            fused = producer_fused[src]
        if kind in ("conv", "dwconv") or fused:
            for o in node.output:
                producer_fused[o] = fused or name
        nodes.append(NodeCost(name, node.op_type, kind, float(macs), float(w), float(ins),
                              float(out), fused))
    return NetworkCost(tuple(nodes), g.name)
