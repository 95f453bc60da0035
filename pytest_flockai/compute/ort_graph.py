"""The graph ONNX Runtime runs for a quantized model in the QDQ format.

``analyze`` absorbs each layer's QuantizeLinear / DequantizeLinear nodes into the layer
(``_fusion.fuse_qdq``): one int8 kernel per layer, as TensorRT, OpenVINO and TF Lite run
it. ONNX Runtime's CPU provider does that only where a group matches one of its QDQ
selectors exactly (DequantizeLinear -> op -> QuantizeLinear, its "QDQ format" docs); an
exporter that writes a Transpose, a Pad or a Clip between them leaves the layer in float,
between separate Dequantize and Quantize passes. ``tf2onnx --tflite`` does this to a TF
Lite int8 model: ONNX Runtime fuses 23 of MobileNetV2's 52 convolutions and 11 of
EfficientNet-B0's 81 (measured with its optimizer, ONNX Runtime 1.32), and runs the
int8 graph 1.7x and 2.9x slower than the float one on an x86 host, where absorbing every
pair had predicted it 3.4x faster.

``as_run(cost)``: for a QDQ graph's cost (its proto in ``meta["_graph"]``), the cost of
the graph ONNX Runtime's own optimizer writes (``ORT_ENABLE_EXTENDED``: the fusions, not
the x86-only layout transforms of the level above), its fused int8 operators at int8, its
float layers marked ``in_float``, its Q/DQ nodes passes of their own; ``cost`` itself when
ONNX Runtime fuses every quantized layer (``quantize_static``'s graphs), or when the
optimizer cannot run (e.g. weights in external files). Memoised on the cost
(``meta["_as_run"]``) and on the proto's bytes, so that a task's model analysed anew for
each flight is optimized once (``_BY_BYTES``).
"""

from __future__ import annotations

import hashlib
import os
import tempfile
from dataclasses import replace

import onnx
import onnxruntime as ort

from .graph import NetworkCost, analyze

#: (SHA-256 of the shape-fixed proto, the cost's name) -> the graph ONNX Runtime runs, or
#: None where it fuses everything (the cost itself); the last ``CACHED`` models
_BY_BYTES: dict = {}
CACHED = 16


def as_run(cost: NetworkCost) -> NetworkCost:
    """See the module docstring."""
    meta = cost.meta
    if "_as_run" not in meta:
        proto = meta.get("_graph")
        if proto is None:
            return cost
        key = (hashlib.sha256(proto.SerializeToString()).hexdigest(), cost.name)
        if key not in _BY_BYTES:
            if len(_BY_BYTES) >= CACHED:
                _BY_BYTES.pop(next(iter(_BY_BYTES)))
            run = _as_run(cost, proto)
            _BY_BYTES[key] = None if run is cost else run
        meta["_as_run"] = _BY_BYTES[key] or cost
    return meta["_as_run"]


def _as_run(cost: NetworkCost, proto) -> NetworkCost:
    try:
        with tempfile.TemporaryDirectory() as tmp:
            src, out = os.path.join(tmp, "in.onnx"), os.path.join(tmp, "run.onnx")
            onnx.save(proto, src)
            so = ort.SessionOptions()
            so.graph_optimization_level = ort.GraphOptimizationLevel.ORT_ENABLE_EXTENDED
            so.optimized_model_filepath = out
            so.log_severity_level = 3
            ort.InferenceSession(src, so, providers=["CPUExecutionProvider"])
            ran = onnx.load(out)
        run = analyze(ran, cost.input_shape, allow_uncounted=True, name=cost.name, as_run=True)
    except Exception:  # noqa: BLE001 (ONNX Runtime's own exception types): keep the QDQ cost
        return cost
    floats = [n for n in run.nodes if n.in_float]
    if not floats:
        return cost
    layers = [n for n in run.nodes if n.kind in ("conv", "dwconv", "matmul")
              and n.fused_into is None]
    return replace(run, meta={**run.meta, "int8": "qdq", "onnxruntime_float_layers":
                              f"{len(floats)} of {len(layers)}"})


__all__ = ["as_run"]
