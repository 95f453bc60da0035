"""Quantized (int8) ONNX graphs, as ``onnxruntime.quantization`` writes them, run as int8
layers: the activations' QuantizeLinear / DequantizeLinear nodes are absorbed into the layer
they wrap (one int8 kernel, as ONNX Runtime, TensorRT, OpenVINO and TF Lite run it), and the
graph runs at int8 unless the call, the task or the drone states a precision."""

import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import onnx
import pytest
from onnx import TensorProto, helper, numpy_helper
from onnxruntime.quantization import CalibrationDataReader, QuantFormat, quantize_static

import pytest_flockai as fa
from pytest_flockai.cli import main
from pytest_flockai.compute import runtimes
from pytest_flockai.compute.graph import FOLDED, analyze
from pytest_flockai.compute.ort_graph import as_run
from pytest_flockai.compute.predict import predict_latency
from pytest_flockai.compute.runtimes import QuantizedModelWarning

SIDE = 64
DATA = Path(__file__).resolve().parent / "data"           # data/make_tflite.py


def _float_net(path):
    """Four 3x3 Conv + ReLU blocks, a global pool and a classifier (opset 17)."""
    rng = np.random.default_rng(5)
    nodes, inits, src, c = [], [], "x", 3
    for i, co in enumerate((16, 32, 32, 64)):
        nodes += [helper.make_node("Conv", [src, f"w{i}", f"b{i}"], [f"c{i}"], name=f"conv{i}",
                                   pads=[1, 1, 1, 1], kernel_shape=[3, 3],
                                   strides=[2, 2] if i % 2 else [1, 1]),
                  helper.make_node("Relu", [f"c{i}"], [f"r{i}"], name=f"relu{i}")]
        inits += [numpy_helper.from_array(0.1 * rng.standard_normal((co, c, 3, 3)).astype(
            np.float32), f"w{i}"), numpy_helper.from_array(np.zeros(co, np.float32), f"b{i}")]
        src, c = f"r{i}", co
    nodes += [helper.make_node("GlobalAveragePool", [src], ["gp"], name="gap"),
              helper.make_node("Flatten", ["gp"], ["fl"], name="flat"),
              helper.make_node("Gemm", ["fl", "wf"], ["y"], name="fc", transB=1)]
    inits.append(numpy_helper.from_array(rng.standard_normal((10, 64)).astype(np.float32), "wf"))
    g = helper.make_graph(nodes, "net", [helper.make_tensor_value_info(
        "x", TensorProto.FLOAT, [1, 3, SIDE, SIDE])], [helper.make_tensor_value_info(
            "y", TensorProto.FLOAT, [1, 10])], inits)
    m = helper.make_model(g, opset_imports=[helper.make_opsetid("", 17)])
    m.ir_version = 8
    onnx.save(m, str(path))
    return path


class _Frames(CalibrationDataReader):
    def __init__(self):
        self.rng, self.n = np.random.default_rng(0), 0

    def get_next(self):
        self.n += 1
        return ({"x": self.rng.standard_normal((1, 3, SIDE, SIDE)).astype(np.float32)}
                if self.n <= 3 else None)


@pytest.fixture(scope="module")
def nets(tmp_path_factory):
    d = tmp_path_factory.mktemp("quant")
    f = _float_net(d / "float.onnx")
    out = {"float": f}
    for name, fmt in (("qdq", QuantFormat.QDQ), ("qop", QuantFormat.QOperator)):
        out[name] = d / f"{name}.onnx"
        quantize_static(str(f), str(out[name]), _Frames(), quant_format=fmt)
    return out


def test_a_qdq_graph_runs_as_its_int8_layers(nets):
    f, q = analyze(nets["float"]), analyze(nets["qdq"])
    assert "int8" not in f.meta and q.meta["int8"] == "qdq"
    # the quantizer writes a Q/DQ pair around every activation; each is absorbed into the
    # layer that writes (or, for the graph input's copy, reads) it
    qdq = [n for n in q.nodes if n.op_type in ("QuantizeLinear", "DequantizeLinear")]
    assert len(qdq) >= 10
    names = {n.name for n in q.nodes}
    assert sum(n.fused_into == FOLDED for n in qdq) == 9              # the weights' DQ
    assert all(n.fused_into in names or n.fused_into == FOLDED for n in qdq if n.fused_into)
    assert [n.name for n in q.run_nodes if n in qdq] == ["x_QuantizeLinear"]   # float -> int8
    by = {n.name: n for n in q.nodes}
    assert by["r0_QuantizeLinear"].fused_into == by["r0_DequantizeLinear"].fused_into == "conv0"
    run = [n.op_type for n in q.run_nodes]
    assert run.count("Conv") == 4 and run.count("Gemm") == 1
    # the same layers, the same MACs but the ReLUs the quantizer folded into the ranges
    relu = sum(n.macs for n in f.nodes if n.op_type == "Relu")
    assert q.macs == f.macs - relu
    # so it predicts as the float graph at int8, not slower than the float graph at fp32
    for dev, rt in (("raspberry-pi-4", "onnxruntime"), ("jetson-orin-nano", "tensorrt")):
        pq = predict_latency(nets["qdq"], dev, runtime=rt)
        pf8 = predict_latency(nets["float"], dev, runtime=rt, precision="int8")
        pf = predict_latency(nets["float"], dev, runtime=rt)
        assert pq.precision == "int8" and pf.precision != "int8"
        assert pq.seconds == pytest.approx(pf8.seconds, rel=0.1), dev
        assert pq.seconds < pf.seconds, dev
    # the QOperator format (QLinearConv, ONNX Runtime's QGemm and QLinearGlobalAveragePool)
    o = analyze(nets["qop"])
    assert o.meta["int8"] == "qoperator" and o.uncounted == () and o.macs >= q.macs - 64 * 10
    assert predict_latency(nets["qop"], "raspberry-pi-4").precision == "int8"


def test_a_stated_precision_wins_and_int8_where_it_cannot_run_warns(nets):
    p = predict_latency(nets["qdq"], "raspberry-pi-4", precision="fp32")
    assert p.precision == "fp32"
    # the Jetson Nano's Maxwell GPU has no int8 path in TensorRT: its default, with a warning
    with pytest.warns(QuantizedModelWarning, match=r"quantized \(int8, qdq\).*'tensorrt'.*"
                                                   r"jetson-nano-10w"):
        p = predict_latency(nets["qdq"], "jetson-nano-10w", runtime="tensorrt")
    assert p.precision == "fp16"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        predict_latency(nets["float"], "jetson-nano-10w", runtime="tensorrt")


def test_a_task_on_a_quantized_model_runs_at_int8_unless_told(nets):
    model = fa.ml.OnnxModel(nets["qdq"])

    def p50(drone_kw=None, **task_kw):
        if drone_kw is not None:
            drone = fa.drone("dji-mavic-2-pro", device="raspberry-pi-4", **drone_kw)
            r = fa.Mission(drone, fa.pilots.Hover(altitude=3.0, duration=3.0), seed=0,
                           tasks=[fa.Task(model, period_s=1.0, alert="result")]).run()
            lat = {e["compute_s"] for e in r.events if e.get("kind") == "inference"}
            assert len(lat) == 1                   # one frame size: one latency
            return lat.pop()
        task = fa.Task(model, period_s=1.0, device="raspberry-pi-4", alert="result", **task_kw)
        r = fa.ml.TaskRunner(task).bind(0)
        r.on_frame(0.0, np.zeros((SIDE, SIDE, 3), np.uint8))
        r.advance(5.0)
        return r.kpis()["inference_latency_p50_s"]

    int8 = predict_latency(nets["qdq"], "raspberry-pi-4", precision="int8").seconds
    fp32 = predict_latency(nets["qdq"], "raspberry-pi-4", precision="fp32").seconds
    assert p50() == pytest.approx(int8)
    assert p50(precision="fp32") == pytest.approx(fp32)
    assert p50(drone_kw={}) == pytest.approx(int8)
    assert p50(drone_kw={"precision": "fp32"}) == pytest.approx(fp32)
    assert fp32 > 1.2 * int8


def test_weight_only_quantization_computes_in_float():
    """int8 weights dequantized for a float convolution (no activation is quantized) are a
    smaller file, not an int8 network: no int8 default."""
    w = numpy_helper.from_array(np.ones((8, 3, 3, 3), np.int8), "w_q")
    scale = numpy_helper.from_array(np.asarray(0.01, np.float32), "w_s")
    nodes = [helper.make_node("DequantizeLinear", ["w_q", "w_s"], ["w"], name="w/DQ"),
             helper.make_node("Conv", ["x", "w"], ["y"], name="conv", pads=[1, 1, 1, 1])]
    g = helper.make_graph(nodes, "wo", [helper.make_tensor_value_info(
        "x", TensorProto.FLOAT, [1, 3, SIDE, SIDE])], [helper.make_tensor_value_info(
            "y", TensorProto.FLOAT, None)], [w, scale])
    m = helper.make_model(g, opset_imports=[helper.make_opsetid("", 17)])
    m.ir_version = 8
    cost = analyze(m)
    assert "int8" not in cost.meta and cost.nodes[0].fused_into == FOLDED
    assert predict_latency(cost, "raspberry-pi-4").precision == "fp32"


def test_a_dynamically_quantized_lstm_counts_as_its_lstm(tmp_path):
    """``quantize_dynamic`` writes an LSTM as ONNX Runtime's DynamicQuantizeLSTM (int8 W
    and R, stored transposed): the same multiply-accumulates as the float LSTM, run at int8."""
    from onnxruntime.quantization import quantize_dynamic
    rng = np.random.default_rng(1)
    seq, inp, hid = 12, 16, 32
    w = rng.standard_normal((1, 4 * hid, inp)).astype(np.float32)
    r = rng.standard_normal((1, 4 * hid, hid)).astype(np.float32)
    g = helper.make_graph(
        [helper.make_node("LSTM", ["x", "W", "R"], ["y", "yh"], name="lstm", hidden_size=hid)],
        "lstm", [helper.make_tensor_value_info("x", TensorProto.FLOAT, [seq, 1, inp])],
        [helper.make_tensor_value_info("y", TensorProto.FLOAT, [seq, 1, 1, hid])],
        [numpy_helper.from_array(w, "W"), numpy_helper.from_array(r, "R")])
    m = helper.make_model(g, opset_imports=[helper.make_opsetid("", 17)])
    m.ir_version = 8
    onnx.save(m, str(tmp_path / "f.onnx"))
    quantize_dynamic(str(tmp_path / "f.onnx"), str(tmp_path / "q.onnx"))
    q = onnx.load(str(tmp_path / "q.onnx"))
    assert [n.op_type for n in q.graph.node if n.domain == "com.microsoft"] == ["DynamicQuantizeLSTM"]
    fq, ff = analyze(tmp_path / "q.onnx"), analyze(tmp_path / "f.onnx")
    assert fq.macs == ff.macs == seq * (w.size + r.size)
    assert fq.meta["int8"] == "dynamic"
    assert predict_latency(fq, "raspberry-pi-5", runtime="onnxruntime").precision == "int8"


def _half_net(path):
    """The float net with fp16 weights and input (what ``model.half()`` exports)."""
    m = onnx.load(str(_float_net(path)))
    for t in m.graph.initializer:
        t.CopyFrom(numpy_helper.from_array(numpy_helper.to_array(t).astype(np.float16), t.name))
    for v in list(m.graph.input) + list(m.graph.output):
        v.type.tensor_type.elem_type = TensorProto.FLOAT16
    onnx.save(m, str(path))
    return path


def test_an_fp16_graph_runs_at_fp16_where_it_can_and_warns_where_not(nets, tmp_path, capsys):
    half = analyze(_half_net(tmp_path / "half.onnx"))
    assert half.meta.get("fp16") is True and "fp16" not in analyze(nets["float"]).meta
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        p = predict_latency(half, "jetson-orin-nano", runtime="tensorrt")
        assert p.precision == "fp16"
        assert predict_latency(half, "raspberry-pi-5", runtime="ncnn").precision == "fp16"
        # a stated precision wins, silently
        assert predict_latency(half, "raspberry-pi-4", runtime="ncnn", precision="fp32").precision == "fp32"
    with pytest.warns(runtimes.HalfModelWarning, match="weights are fp16 but runtime 'ncnn' on "
                                                       "the cpu of computer 'raspberry-pi-4'"):
        p4 = predict_latency(half, "raspberry-pi-4", runtime="ncnn")      # Cortex-A72: no fp16
    assert p4.precision == "fp32"
    assert p4.seconds == predict_latency(nets["float"], "raspberry-pi-4", runtime="ncnn").seconds
    # the command line stars those rows and says why (the int8 note would be wrong here)
    capsys.readouterr()
    assert main(["predict-latency", str(tmp_path / "half.onnx"), "--computer",
                 "raspberry-pi-4", "--runtime", "ncnn"]) == 0
    out = capsys.readouterr().out
    assert "ncnn/cpu/fp32* " in out and "weights are fp16 and this deployment cannot run fp16" in out
    assert "quantized" not in out and "~" not in out            # ncnn/cpu/fp32 was fitted
    # fp16 on the Pi 5's CPU: no published row was fitted; the rows say so
    assert p.tuned is True and predict_latency(half, "raspberry-pi-5", runtime="ncnn").tuned \
        is False
    assert main(["predict-latency", str(tmp_path / "half.onnx"), "--computer",
                 "raspberry-pi-5", "--runtime", "ncnn"]) == 0
    out = capsys.readouterr().out
    assert "ncnn/cpu/fp16~" in out and "~ no published measurement of this runtime" in out


def test_a_float_graph_on_the_edge_tpu_warns_that_it_needs_int8(nets):
    with pytest.warns(runtimes.ModelPrecisionWarning, match="runs only full-integer"):
        assert predict_latency(nets["float"], "coral-dev-board", runtime="edgetpu").precision == "int8"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        predict_latency(nets["qdq"], "coral-dev-board", runtime="edgetpu")


def test_a_qdq_silu_fuses_as_its_float_graph_does(tmp_path):
    """SiLU (x * Sigmoid(x)) after a convolution, quantized: its Q/DQ pairs sit between the
    convolution, the gate and the Mul; TensorRT fuses the layer through them as in float, so
    the QDQ graph and its float graph run the same kernels at int8 (it ran two more passes
    per layer). ONNX Runtime does not (below)."""
    rng = np.random.default_rng(2)
    nodes, inits, src, c = [], [], "x", 3
    for i, co in enumerate((16, 32, 32)):
        nodes += [helper.make_node("Conv", [src, f"w{i}", f"b{i}"], [f"c{i}"], name=f"conv{i}",
                                   pads=[1, 1, 1, 1], kernel_shape=[3, 3]),
                  helper.make_node("Sigmoid", [f"c{i}"], [f"s{i}"], name=f"sig{i}"),
                  helper.make_node("Mul", [f"c{i}", f"s{i}"], [f"m{i}"], name=f"silu{i}")]
        inits += [numpy_helper.from_array(0.1 * rng.standard_normal((co, c, 3, 3)).astype(
            np.float32), f"w{i}"), numpy_helper.from_array(np.zeros(co, np.float32), f"b{i}")]
        src, c = f"m{i}", co
    g = helper.make_graph(nodes, "silu", [helper.make_tensor_value_info(
        "x", TensorProto.FLOAT, [1, 3, SIDE, SIDE])], [helper.make_tensor_value_info(
            src, TensorProto.FLOAT, [1, c, SIDE, SIDE])], inits)
    m = helper.make_model(g, opset_imports=[helper.make_opsetid("", 17)])
    m.ir_version = 8
    onnx.save(m, str(tmp_path / "f.onnx"))
    quantize_static(str(tmp_path / "f.onnx"), str(tmp_path / "q.onnx"), _Frames(),
                    quant_format=QuantFormat.QDQ)
    q, f = analyze(tmp_path / "q.onnx"), analyze(tmp_path / "f.onnx")
    assert {n.op_type for n in q.nodes if n.op_type in ("Sigmoid", "Mul") and n.fused_into}
    a = predict_latency(q, "jetson-orin-nano", runtime="tensorrt").seconds
    b = predict_latency(f, "jetson-orin-nano", runtime="tensorrt", precision="int8").seconds
    assert a == pytest.approx(b, rel=0.05)
    # ONNX Runtime's optimizer fuses none of these layers (its output, ONNX Runtime 1.32): it
    # runs them in float between Q/DQ passes, 1.7x slower than the float graph (measured on
    # the x86 development host, one thread)
    run = as_run(q)
    assert sum(n.in_float for n in run.nodes) == 3
    for computer in ("raspberry-pi-4", "raspberry-pi-5"):
        a = predict_latency(q, computer, runtime="onnxruntime")
        assert a.precision == "int8"
        assert a.seconds > predict_latency(f, computer, runtime="onnxruntime").seconds


def test_onnx_runtime_runs_the_layers_it_does_not_fuse_in_float(nets):
    """tf2onnx's conversion of a TF Lite int8 model writes a Transpose between the input's
    DequantizeLinear and the first Conv: ONNX Runtime's optimizer fuses that layer (and the
    classifier's MatMul) into no int8 operator. On onnxruntime those layers are predicted
    in float with their Q/DQ passes; TF Lite, which runs the .tflite in int8 end to end,
    keeps every pair absorbed; a quantize_static graph, all fused, is unchanged."""
    path = DATA / "tiny_cnn_int8_tf2onnx.onnx"
    cost = analyze(path)
    assert cost.meta["int8"] == "qdq" and "_graph" in cost.meta
    assert "_graph" not in cost.to_csv()                    # the model is not written out
    run = as_run(cost)
    floats = [n for n in run.nodes if n.in_float]
    assert floats and {n.op_type for n in floats} <= {"Conv", "FusedConv", "MatMul", "Gemm"}
    assert any(n.op_type == "QLinearConv" for n in run.nodes)          # the one it fuses
    assert run.meta["onnxruntime_float_layers"].endswith(f"of {len(floats) + 1}")
    absorbed = replace(cost, meta={k: v for k, v in cost.meta.items() if k != "_graph"})
    for dev in ("raspberry-pi-4", "raspberry-pi-5"):
        now = predict_latency(path, dev, runtime="onnxruntime")
        every = predict_latency(absorbed, dev, runtime="onnxruntime")
        assert now.precision == "int8" and now.seconds > every.seconds, dev
        assert predict_latency(path, dev, runtime="tflite").seconds == pytest.approx(
            predict_latency(absorbed, dev, runtime="tflite").seconds)
        assert predict_latency(path, dev, runtime="onnxruntime", precision="fp32").seconds \
            == pytest.approx(predict_latency(absorbed, dev, runtime="onnxruntime",
                                             precision="fp32").seconds)
    q = analyze(nets["qdq"])
    assert as_run(q) is q                   # ONNX Runtime fuses quantize_static's graph
