"""How runtimes fuse an ONNX graph's nodes (``fused_into`` of ``graph.NodeCost``).

- ``fuse``: a Conv or ConvTranspose absorbs a following BatchNormalization, then one
  activation (or a gated SiLU / hard-swish); a MatMul or Gemm absorbs a bias ``Add``, then an
  activation (the table in ``graph``'s docstring).
- ``fuse_qdq``: in a quantized graph in the QDQ format (``QuantizeLinear`` /
  ``DequantizeLinear`` pairs around each layer, as ``onnxruntime.quantization``, TensorRT's
  and OpenVINO's quantizers and ``torch.ao`` exports write it), the activations' Q/DQ nodes
  are absorbed into the layer they wrap. ONNX Runtime's graph optimizer fuses a DQ -> op -> Q
  pattern into the quantized operator (its docs, "Quantize ONNX models", on the QDQ format),
  TensorRT fuses Q/DQ layers into the quantized layer (developer guide, "Explicit
  quantization"), OpenVINO's low-precision transformations do the same, and TF Lite runs a
  quantized model's ops as int8 kernels end to end: one int8 kernel per layer, with no
  separate pass over the tensor (paraphrased, not quoted). A Q/DQ
  pair between two layers is absorbed into the layer that writes the tensor; a DQ that
  reads a graph input's quantized copy into the layer that reads it. A QuantizeLinear on a
  graph input stays: it is a real pass that turns the float input into int8.
- ``dispatched``: the nodes a runtime runs, with the gated activations (SiLU, hard-swish)
  and, for eager PyTorch, every activation a pass of its own where that runtime does not fuse
  them (``GATE_FUSED``, ``ACT_UNFUSED``).
- ``quantization``: how a graph is quantized: ``"qdq"``, ``"qoperator"`` (QLinearConv,
  QLinearMatMul, ConvInteger, MatMulInteger, ONNX Runtime's QLinear* operators),
  ``"dynamic"`` (DynamicQuantizeLinear + MatMulInteger / ConvInteger, ONNX Runtime's
  DynamicQuantizeLSTM), or None.
"""

from __future__ import annotations

from dataclasses import replace

import onnx

from ._ops import ACTIVATIONS

#: ``fused_into`` of a node that runtimes fold into a constant before running
FOLDED = "<constant>"
QDQ = frozenset(("QuantizeLinear", "DequantizeLinear"))
QOPERATOR = frozenset(("QLinearConv", "QLinearMatMul", "ConvInteger", "MatMulInteger", "QGemm",
                       "QLinearAdd", "QLinearMul", "MatMulIntegerToFloat",
                       "DynamicQuantizeMatMul"))


def quantization(g) -> str | None:
    """``"dynamic"``, ``"qoperator"``, ``"qdq"`` or None: how ``g``'s layers are quantized."""
    ops = {n.op_type for n in g.node}
    if ops & {"DynamicQuantizeLinear", "DynamicQuantizeMatMul", "MatMulIntegerToFloat",
              "DynamicQuantizeLSTM"}:
        return "dynamic"
    if ops & QOPERATOR:
        return "qoperator"
    # QDQ: activations are quantized (a QuantizeLinear of a computed tensor); a graph whose
    # only DequantizeLinear nodes read stored weights is weight-only quantized and computes
    # in float
    consts = set(_constant_names(g))
    if any(n.op_type == "QuantizeLinear" and n.input and n.input[0] not in consts
           for n in g.node):
        return "qdq"
    return None


def half_weights(g) -> bool:
    """Whether ``g`` computes in fp16: most of its convolutions' and matrix products' stored
    weights are fp16 (``model.half()`` exported, or onnxconverter-common's
    ``convert_float_to_float16``, which keeps fp32 inputs behind Cast nodes)."""
    f16 = {t.name for t in g.initializer if t.data_type == onnx.TensorProto.FLOAT16}
    f32 = {t.name for t in g.initializer if t.data_type == onnx.TensorProto.FLOAT}
    w = [n.input[1] for n in g.node if n.op_type in ("Conv", "ConvTranspose", "MatMul", "Gemm")
         and len(n.input) > 1 and n.input[1] in f16 | f32]
    return bool(w) and 2 * sum(x in f16 for x in w) > len(w)


def fuse_qdq(g, nodes: list) -> list:
    """Absorb the activations' QuantizeLinear / DequantizeLinear nodes into the layer they
    wrap (the module docstring); folded (weight) DQ nodes stay folded."""
    producer, consumers = _links(g)
    head: dict[int, str] = {}

    def owner(i: int) -> str | None:
        """The layer node ``i`` runs as part of (itself, unless fused)."""
        if i in head:
            return head[i]
        f = nodes[i].fused_into
        return nodes[i].name if f is None else (None if f == FOLDED else f)

    for i, node in enumerate(g.node):
        if node.op_type not in QDQ or nodes[i].fused_into is not None or not node.input:
            continue
        src = producer.get(node.input[0])
        layer = owner(src) if src is not None else None
        if layer is not None:
            head[i] = layer                    # written by a layer (or its Q): absorbed
        elif node.op_type == "DequantizeLinear" and node.output:
            reads = [c for c in consumers.get(node.output[0], []) if g.node[c].op_type not in QDQ]
            if len(reads) == 1 and nodes[reads[0]].fused_into is None:
                head[i] = nodes[reads[0]].name  # a graph input's int8 copy, read by one layer
    return [replace(n, fused_into=head[i]) if i in head else n for i, n in enumerate(nodes)]


def fuse(g, nodes: list) -> list:
    """Mark BatchNorm / bias / activation nodes fused into the Conv or MatMul before them."""
    _, consumers = _links(g)
    outputs = {o.name for o in g.output}
    fused: dict[int, str] = {}
    inits = frozenset(_constant_names(g))

    def only(t):
        c = consumers.get(t, [])
        return c[0] if len(c) == 1 and t not in outputs and c[0] not in fused else None

    def through(t):
        """``t``, or past a QuantizeLinear -> DequantizeLinear pair that alone reads it (a
        QDQ graph: the pair is absorbed by ``fuse_qdq``, the layer fuses as in float)."""
        q = only(t)
        if q is not None and g.node[q].op_type == "QuantizeLinear":
            dq = only(g.node[q].output[0])
            if dq is not None and g.node[dq].op_type == "DequantizeLinear":
                return g.node[dq].output[0]
        return t

    for i, node in enumerate(g.node):
        op = node.op_type
        if nodes[i].fused_into is not None or i in fused or not node.output:
            continue
        if op not in ("Conv", "ConvTranspose", "MatMul", "Gemm"):
            continue
        head, t = nodes[i].name, node.output[0]
        j = only(t)
        first = "BatchNormalization" if op.startswith("Conv") else "Add"
        if j is not None and g.node[j].op_type == first and (
                first != "Add" or all(x == t or x in inits for x in g.node[j].input)):
            fused[j], t = head, g.node[j].output[0]
            j = only(t)
        t = through(t)                      # past a Q/DQ pair, or ``t`` itself
        j = only(t)
        if j is not None and g.node[j].op_type in ACTIVATIONS:
            fused[j] = head
            continue
        c = consumers.get(t, [])          # x * Sigmoid(x), x * HardSigmoid(x)
        if len(c) == 2 and t not in outputs and not (set(c) & set(fused)):
            a, b = sorted(c, key=lambda k: g.node[k].op_type != "Mul")
            gate = g.node[b]
            if gate.op_type not in ("Sigmoid", "HardSigmoid") or not gate.output:
                continue
            gt = through(gate.output[0])
            if (g.node[a].op_type == "Mul" and gt in g.node[a].input
                    and consumers.get(gt) == [a]):
                fused[a] = fused[b] = head
    return [replace(n, fused_into=fused[i]) if i in fused else n for i, n in enumerate(nodes)]


def fuse_patterns(g, nodes: list) -> list:
    """Fold the element-wise chains an exporter writes for one operator into one kernel, as
    the runtimes' graph optimizers do: GELU written with Erf (``x * 0.5 * (1 + erf(x /
    sqrt 2))``, the legacy ``torch.onnx`` exporter's form; ONNX Runtime's GeluFusion, TensorRT's
    and OpenVINO's GELU fusions) and layer normalization written as ReduceMean, Sub, Pow,
    ReduceMean, Add, Sqrt, Div and the affine Mul and Add (opsets before 17; ONNX Runtime's
    LayerNormFusion, OpenVINO's MVN fusion). The chain's last node runs it: it reads the
    chain's input and writes its output once, one operation per element, as a ``Gelu`` or
    ``LayerNormalization`` node of a newer exporter does; the others are fused into it."""
    outputs = {o.name for o in g.output}
    consts = frozenset(_constant_names(g))
    prod, cons = _links(g)
    taken: set[int] = set()

    def free(i) -> bool:
        return i is not None and i not in taken and nodes[i].fused_into is None

    def next_of(i, op):
        """The one consumer of node ``i``'s output, if it is ``op`` and free."""
        t = g.node[i].output[0]
        c = cons.get(t, [])
        return c[0] if len(c) == 1 and t not in outputs and g.node[c[0]].op_type == op \
            and free(c[0]) else None

    def other(i, t):
        """The input of node ``i`` that is not ``t``."""
        ins = list(g.node[i].input)
        return ins[1 - ins.index(t)] if len(ins) == 2 and t in ins else None

    chains: list[list[int]] = []
    for i, node in enumerate(g.node):
        if not free(i) or not node.input:
            continue
        if node.op_type == "Erf":                   # Div/Mul -> Erf -> Add -> Mul(x) [-> Mul]
            p = prod.get(node.input[0])
            if p is None or not free(p) or g.node[p].op_type not in ("Div", "Mul"):
                continue
            x = g.node[p].input[0]
            if g.node[p].input[1] not in consts or x in consts:
                continue
            a = next_of(i, "Add")
            m = next_of(a, "Mul") if a is not None else None
            if m is None or other(a, node.output[0]) not in consts:
                continue
            chain = [p, i, a, m]
            mx = other(m, g.node[a].output[0])
            h = prod.get(mx) if mx is not None else None
            if mx != x and not (h is not None and free(h) and g.node[h].op_type == "Mul"
                                and cons.get(mx) == [m] and other(h, x) in consts):
                continue                         # x * (1 + erf), or (x * 0.5) * (1 + erf)
            if mx != x:
                chain.insert(0, h)
            f = next_of(m, "Mul")
            if f is not None and other(f, g.node[m].output[0]) in consts:
                chain.append(f)
            chains.append(chain)
        elif node.op_type == "ReduceMean":          # the layer-norm chain, from its mean
            x = node.input[0]
            sub = next_of(i, "Sub")
            if sub is None or list(g.node[sub].input) != [x, node.output[0]]:
                continue
            d = g.node[sub].output[0]
            two = sorted(cons.get(d, []), key=lambda k: g.node[k].op_type != "Div")
            if len(two) != 2 or d in outputs or not all(free(k) for k in two):
                continue
            div, sq = two
            if g.node[div].op_type != "Div" or g.node[sq].op_type not in ("Pow", "Mul"):
                continue
            r2 = next_of(sq, "ReduceMean")
            eps = next_of(r2, "Add") if r2 is not None else None
            rt = next_of(eps, "Sqrt") if eps is not None else None
            if rt is None or list(g.node[div].input) != [d, g.node[rt].output[0]]:
                continue
            chain = [i, sub, sq, r2, eps, rt, div]
            for op in ("Mul", "Add"):                # the affine scale and shift
                k = next_of(chain[-1], op)
                if k is None or other(k, g.node[chain[-1]].output[0]) not in consts:
                    break
                chain.append(k)
            chains.append(chain)
        else:
            continue
        taken.update(chains[-1])

    out = list(nodes)
    for chain in chains:
        last = chain[-1]
        n = out[last]
        size = n.out_elems
        out[last] = replace(n, kind="elementwise", macs=size, in_elems=size,
                            weight_elems=sum(out[k].weight_elems for k in chain))
        for k in chain[:-1]:
            out[k] = replace(out[k], fused_into=n.name)
    return out


def _links(g) -> tuple[dict[str, int], dict[str, list[int]]]:
    """({tensor: the node writing it}, {tensor: the nodes reading it}) of the graph ``g``."""
    producer: dict[str, int] = {}
    consumers: dict[str, list[int]] = {}
    for i, node in enumerate(g.node):
        for o in node.output:
            producer[o] = i
        for t in node.input:
            consumers.setdefault(t, []).append(i)
    return producer, consumers


def _constant_names(g) -> list[str]:
    """Names of the graph's initializers, ``Constant`` outputs and ``Identity`` copies of
    them (the legacy exporter reads shared weights and biases through Identity nodes)."""
    out = [t.name for t in g.initializer] + [n.output[0] for n in g.node
                                             if n.op_type == "Constant" and n.output]
    known = set(out)
    for n in g.node:                            # topological order: chains of copies too
        if n.op_type == "Identity" and n.input and n.input[0] in known and n.output:
            out.append(n.output[0])
            known.add(n.output[0])
    return out


#: runtimes that fuse a gated activation ``x * gate(x)`` into the convolution before it, by
#: gate. TensorRT fuses point-wise chains into the convolution's epilogue (TensorRT developer
#: guide, "Layer fusion": PointWise fusion) and OpenVINO's CPU plugin fuses Swish and
#: HSwish as post-ops; ncnn's Convolution fuses hard-swish (``activation_type`` 6) but has no
#: Swish activation, so SiLU runs as its own Swish layer (ncnn ``src/layer/convolution``,
#: ``fuse_convolution_activation`` in ``tools/ncnnoptimize``); ONNX Runtime's FusedConv takes
#: Relu / Sigmoid / Tanh / LeakyRelu / Clip / HardSigmoid, never the Mul after them; TFLite
#: runs LOGISTIC / HARD_SWISH and MUL as their own ops; eager PyTorch runs SiLU as one op.
#: Any other runtime/gate pair: one separate element-wise pass (read x, write x * gate(x)).
GATE_FUSED = {"tensorrt": ("Sigmoid", "HardSigmoid"), "openvino": ("Sigmoid", "HardSigmoid"),
              "edgetpu": ("Sigmoid", "HardSigmoid"), "ncnn": ("HardSigmoid",)}


#: runtimes that fuse no activation into the convolution before it: eager PyTorch calls
#: each module in turn (``nn.ReLU`` after ``nn.Conv2d`` is a second kernel launch and a
#: second pass over the tensor). Fusion in PyTorch is an explicit transformation of the
#: model: ``torch.ao.quantization.quantize_fx.fuse_fx`` ("Fuse modules like conv+bn,
#: conv+bn+relu etc", PyTorch API reference), ``torch.nn.utils.fusion.fuse_conv_bn_eval``,
#: TorchScript freezing or ``torch.compile``. Its gated activations (SiLU, hard-swish) are
#: one kernel each, as ``GATE_FUSED``'s rule already counts.
ACT_UNFUSED = frozenset(("pytorch",))


#: operators that give a new view of their input's buffer, not a copy: ONNX Runtime
#: registers Reshape, Flatten, Squeeze and Unsqueeze as aliasing kernels (output 0 may share
#: input 0's buffer), PyTorch's view/reshape of a contiguous tensor copies nothing, ncnn's
#: converter folds them (Reshape-Transpose-Reshape into one ShuffleChannel pass, the Flatten
#: before InnerProduct away) and TensorRT fuses them into neighbouring shuffle layers. They are
#: dispatched (a kernel launch) but move no data.
VIEWS = frozenset(("Reshape", "Flatten", "Squeeze", "Unsqueeze"))


def dispatched(nodes, runtime: str) -> list:
    """The nodes a runtime runs: the unfused ones (a view, ``VIEWS``, with no bytes to
    move), plus, where the runtime does not fuse a
    gated activation (``GATE_FUSED``), that activation's Mul as one element-wise pass over
    its output (one read, one write, one op per element), and, for the runtimes of
    ``ACT_UNFUSED``, every other activation fused into a convolution or matrix product as its
    own pass (an exporter's chain written for one operator, ``fuse_patterns``, stays one
    kernel: eager PyTorch runs that operator as one)."""
    gates = {n.fused_into: n.op_type for n in nodes
             if n.fused_into and n.op_type in ("Sigmoid", "HardSigmoid")}
    fused = GATE_FUSED.get(runtime, ())
    layers = {n.name for n in nodes if n.kind in ("conv", "dwconv", "matmul")}
    out = []
    for n in nodes:
        if not n.fused_into:
            out.append(replace(n, in_elems=0, out_elems=0) if n.op_type in VIEWS else n)
        elif (runtime in ACT_UNFUSED and n.kind == "elementwise" and n.fused_into in layers
              and n.op_type not in ("Sigmoid", "HardSigmoid", "Mul")):
            out.append(replace(n, fused_into=None))
        elif (n.op_type == "Mul" and n.fused_into in gates
              and gates[n.fused_into] not in fused):
            out.append(replace(n, in_elems=n.out_elems, macs=n.out_elems, fused_into=None))
    return out


__all__ = ["ACT_UNFUSED", "FOLDED", "GATE_FUSED", "QDQ", "QOPERATOR", "VIEWS", "dispatched", "fuse",
           "fuse_patterns", "fuse_qdq", "half_weights", "quantization"]
