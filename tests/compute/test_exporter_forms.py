"""One network, exported two ways, predicts the same: the legacy ``torch.onnx`` exporter
writes GELU as Div, Erf, Add, Mul, Mul and layer normalization (before opset 17) as nine
element-wise nodes, and reads shared weights through Identity nodes; the dynamo exporter
writes ``Gelu`` and ``LayerNormalization``. Runtimes fuse the chains (ONNX Runtime's
GeluFusion and LayerNormFusion), so the layer model runs each as one kernel. Graphs built
here, node by node, in both forms."""

import numpy as np
import onnx
import pytest
from onnx import TensorProto, helper, numpy_helper

from pytest_flockai.compute.graph import analyze
from pytest_flockai.compute.predict import predict_latency

T, D = 49, 96          # tokens, width (a ConvNeXt-T stage-1 block at 56 x 56 / 8)


def _c(name, value):
    return numpy_helper.from_array(np.asarray(value, np.float32), name)


def _block(path, legacy: bool, opset: int):
    """LayerNorm -> MatMul(+bias) -> GELU -> MatMul(+bias), with a residual Add."""
    rng = np.random.default_rng(0)
    inits = [_c("w1", rng.standard_normal((D, 4 * D))), _c("b1", np.zeros(4 * D)),
             _c("w2", rng.standard_normal((4 * D, D))), _c("b2", np.zeros(D)),
             _c("g", np.ones(D)), _c("be", np.zeros(D))]
    n = helper.make_node
    if legacy:
        inits += [_c("two", 2.0), _c("eps", 1e-6), _c("sqrt2", 1.4142135), _c("one", 1.0),
                  _c("half", 0.5)]
        ln = [n("ReduceMean", ["x"], ["m"], axes=[-1]), n("Sub", ["x", "m"], ["d"]),
              n("Pow", ["d", "two"], ["p"]), n("ReduceMean", ["p"], ["v"], axes=[-1]),
              n("Add", ["v", "eps"], ["ve"]), n("Sqrt", ["ve"], ["s"]),
              n("Div", ["d", "s"], ["nx"]), n("Mul", ["nx", "g"], ["ng"]),
              n("Add", ["ng", "be"], ["ln"])]
        gelu = [n("Div", ["h", "sqrt2"], ["hd"]), n("Erf", ["hd"], ["he"]),
                n("Add", ["he", "one"], ["h1"]), n("Mul", ["h", "h1"], ["hm"]),
                n("Mul", ["hm", "half"], ["a"])]
        ident = [n("Identity", ["b1"], ["b1i"]), n("Identity", ["b1i"], ["b1c"])]
        b1 = "b1c"                       # the bias read through a chain of Identity copies
    else:
        ln = [n("LayerNormalization", ["x", "g", "be"], ["ln"], axis=-1, epsilon=1e-6)]
        gelu = [n("Gelu", ["h"], ["a"])]
        ident, b1 = [], "b1"
    nodes = ident + ln + [n("MatMul", ["ln", "w1"], ["mm1"]), n("Add", [b1, "mm1"], ["h"])] \
        + gelu + [n("MatMul", ["a", "w2"], ["mm2"]), n("Add", ["mm2", "b2"], ["o"]),
                  n("Add", ["x", "o"], ["y"])]
    g = helper.make_graph(nodes, "block", [helper.make_tensor_value_info(
        "x", TensorProto.FLOAT, [1, T, D])], [helper.make_tensor_value_info(
            "y", TensorProto.FLOAT, [1, T, D])], inits)
    m = helper.make_model(g, opset_imports=[helper.make_opsetid("", opset)])
    m.ir_version = 9
    onnx.checker.check_model(m)
    onnx.save(m, str(path))
    return path


@pytest.fixture(scope="module")
def forms(tmp_path_factory):
    d = tmp_path_factory.mktemp("forms")
    return {"legacy": analyze(_block(d / "legacy.onnx", True, 13)),
            "new": analyze(_block(d / "new.onnx", False, 20))}


def test_the_legacy_and_the_new_forms_run_the_same_kernels(forms):
    def kernels(c):
        return sorted(n.kind for n in c.nodes if n.fused_into is None and n.kind != "data")
    assert kernels(forms["legacy"]) == kernels(forms["new"])
    # the GELU chain is one element-wise kernel over the hidden tensor; the layer norm one
    # over the block's input; the biases (one through two Identity copies) fused into the
    # MatMuls
    new = {n.op_type: n for n in forms["new"].nodes if n.fused_into is None}
    legacy = [n for n in forms["legacy"].nodes if n.fused_into is None and n.kind != "data"]
    assert sum(n.kind == "elementwise" for n in legacy) == 3       # LN, GELU, residual Add
    assert {n.out_elems for n in legacy if n.kind == "elementwise"} == {T * D, 4 * T * D}
    assert new["Gelu"].in_elems == new["Gelu"].out_elems == 4 * T * D
    def matmul(c):
        return sum(n.macs for n in c.nodes if n.kind == "matmul")
    assert matmul(forms["legacy"]) == matmul(forms["new"]) == 2 * T * D * 4 * D


@pytest.mark.parametrize("computer, runtime", [("raspberry-pi-5", "onnxruntime"),
                                               ("raspberry-pi-4", "tflite"),
                                               ("jetson-orin-nano", "tensorrt"),
                                               ("jetson-nano-10w", "pytorch")])
def test_both_forms_predict_the_same_latency(forms, computer, runtime):
    a = predict_latency(forms["legacy"], computer, runtime=runtime).seconds
    b = predict_latency(forms["new"], computer, runtime=runtime).seconds
    assert a == pytest.approx(b, rel=0.02)


def test_a_chain_that_is_not_the_pattern_stays_apart(tmp_path):
    """Erf whose result also leaves the chain (read by the graph's output) is not GELU."""
    n = helper.make_node
    nodes = [n("Div", ["x", "sqrt2"], ["xd"]), n("Erf", ["xd"], ["e"]),
             n("Add", ["e", "one"], ["e1"]), n("Mul", ["x", "e1"], ["y"])]
    g = helper.make_graph(nodes, "notgelu", [helper.make_tensor_value_info(
        "x", TensorProto.FLOAT, [1, 64])], [
        helper.make_tensor_value_info("y", TensorProto.FLOAT, [1, 64]),
        helper.make_tensor_value_info("e", TensorProto.FLOAT, [1, 64])],
        [_c("sqrt2", 1.4142135), _c("one", 1.0)])
    m = helper.make_model(g, opset_imports=[helper.make_opsetid("", 17)])
    m.ir_version = 9
    onnx.save(m, str(tmp_path / "m.onnx"))
    c = analyze(tmp_path / "m.onnx")
    assert all(n.fused_into is None for n in c.nodes)
