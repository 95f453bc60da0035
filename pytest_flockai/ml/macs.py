"""Count multiply-accumulates (MACs) and parameters of an ONNX graph.

The count is ``pytest_flockai.compute.graph.analyze``'s: shapes through the whole
graph (ONNX shape inference with data propagation, then one ONNX Runtime run for
what inference leaves unknown), after the graph inputs' dynamic dimensions are
fixed (batch 1, spatial size from the caller). The MAC count of one inference is
the sum over nodes (the table in ``compute/graph.py``): Conv ``out_elements *
(C_in / group) * prod(kernel)``, ConvTranspose ``in_elements * (C_out / group) *
prod(kernel)``, Gemm/MatMul ``M * N * K``, pools ``out_elements * prod(kernel)``,
global pools and Reduce* ``in_elements``, element-wise ops, activations, norms
and Resize ``out_elements``, data movement 0. A node that cannot be counted (an
unknown operator, a custom domain, shapes no engine could read) is a
``ConfigError`` naming it; ``allow_uncounted=True`` counts it as 0, warns with the
uncounted share and lists it in ``MacReport.uncounted``.

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

from ..compute._shapes import fix_input_shapes, load_onnx
from ..compute.graph import analyze


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


def _prod(xs) -> int:
    n = 1
    for x in xs:
        n *= int(x)
    return n


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


def count_macs(model, input_shapes: dict | None = None, *,
               allow_uncounted: bool = False) -> MacReport:
    """MACs per inference and parameter count of an ONNX model (ModelProto or path).

    ``input_shapes``: {input name: full shape} for inputs with dynamic dims. A node
    left uncounted is a ConfigError naming it unless ``allow_uncounted`` (a warning).
    """
    name = None
    if not isinstance(model, onnx.ModelProto):
        name = os.path.splitext(os.path.basename(os.fspath(model)))[0]   # as analyze names it
        model = load_onnx(model)
    cost = analyze(model, input_shapes, allow_uncounted=allow_uncounted, name=name)
    return MacReport(macs=int(cost.macs), params=_param_count(model), by_op=cost.by_op(),
                     uncounted=list(cost.uncounted))


__all__ = ["MacReport", "count_macs", "fix_input_shapes", "load_onnx"]
