"""Latency from the network's layers, the runtime and the precision.

Runtimes and precisions a computer cannot run are ConfigErrors naming both; the roofline
responds to what it should (MACs, precision, threads, depthwise layers); a bare MAC count
falls back to the old rule with a warning; the tuning reads the tuning half only; tasks
fly with the predicted latency of their deployment."""

import dataclasses
import math
import warnings

import numpy as np
import onnx
import pytest
from onnx import TensorProto, helper, numpy_helper

import pytest_flockai as fa
from pytest_flockai.compute import published, runtimes, tuning
from pytest_flockai.compute.predict import LatencyFallbackWarning, params_for, predict_latency
from pytest_flockai.errors import ConfigError


def convnet(depthwise=False, channels=32, side=64) -> onnx.ModelProto:
    """Conv-BN-ReLU x3 on a 1x3xSxS input (weights from a fixed seed)."""
    rng = np.random.default_rng(0)
    nodes, inits, name, c_in = [], [], "x", 3
    for i in range(3):
        group = c_in if depthwise and i > 0 else 1
        c_out = c_in if group > 1 else channels
        w = (rng.standard_normal((c_out, c_in // group, 3, 3)) * 0.1).astype(np.float32)
        inits.append(numpy_helper.from_array(w, f"w{i}"))
        for p in ("s", "b", "m", "v"):
            inits.append(numpy_helper.from_array(np.ones(c_out, np.float32), f"{p}{i}"))
        nodes += [helper.make_node("Conv", [name, f"w{i}"], [f"c{i}"], pads=[1, 1, 1, 1],
                                   group=group),
                  helper.make_node("BatchNormalization", [f"c{i}", f"s{i}", f"b{i}", f"m{i}",
                                                          f"v{i}"], [f"n{i}"]),
                  helper.make_node("Relu", [f"n{i}"], [f"r{i}"])]
        name, c_in = f"r{i}", c_out
    g = helper.make_graph(nodes, "net", [helper.make_tensor_value_info(
        "x", TensorProto.FLOAT, [1, 3, side, side])], [helper.make_tensor_value_info(
            name, TensorProto.FLOAT, None)], inits)
    m = helper.make_model(g, opset_imports=[helper.make_opsetid("", 17)])
    m.ir_version = 8
    return m


def test_nine_computers_each_with_a_datasheet():
    names = {"raspberry-pi-4", "raspberry-pi-5", "jetson-nano-5w", "jetson-nano-10w",
             "jetson-orin-nano", "jetson-orin-nano-super", "jetson-orin-nx-16gb",
             "coral-dev-board", "ground-gpu"}
    assert names <= set(fa.devices())
    for n in names:
        d = fa.compute.device(n)
        assert d.units and d.runtimes and d.active_w > d.idle_w > 0 and d.memory_mb > 0
        assert all(v > 0 for u in d.units for _, v in u.peak)
    # the datasheet's figures with their sources (computers.toml)
    pi = fa.compute.device("raspberry-pi-4")
    assert pi.unit("cpu").cores == 4 and pi.bandwidth_gbs > 0
    assert any(k.endswith("clock_ghz_source") for k, _ in pi.sources)
    # no int8 on the Nano's Maxwell GPU, no fp16 arithmetic on the Pi 4's Cortex-A72
    assert "int8" not in fa.compute.device("jetson-nano-10w").unit("gpu").precisions
    assert "fp16" not in pi.unit("cpu").precisions


@pytest.mark.parametrize("kw, words", [
    ({"runtime": "tensorrtt"}, ["runtime", "'tensorrtt'", "tensorrt"]),
    ({"precision": "fp8"}, ["precision", "'fp8'", "fp32, fp16, int8"]),
    ({"target": "tpu"}, ["target", "'tpu'", "cpu, gpu, npu"]),
    ({"threads": 0}, ["threads", "0", ">= 1"]),
])
def test_unknown_names_are_refused_naming_field_value_and_allowed(kw, words):
    with pytest.raises(ConfigError) as e:
        predict_latency(convnet(), "raspberry-pi-4", **kw)
    for w in words:
        assert w in str(e.value)


@pytest.mark.parametrize("computer, kw, words", [
    ("raspberry-pi-4", {"runtime": "tensorrt"}, ["tensorrt", "raspberry-pi-4", "NVIDIA",
                                                 "onnxruntime"]),
    ("coral-dev-board", {"runtime": "edgetpu", "precision": "fp32"},
     ["fp32", "edgetpu", "coral-dev-board", "allowed there: int8"]),
    ("jetson-nano-10w", {"runtime": "tensorrt", "precision": "int8"},
     ["int8", "tensorrt", "jetson-nano-10w"]),
    ("raspberry-pi-4", {"threads": 8}, ["threads", "8", "4 cores"]),
])
def test_what_a_computer_cannot_run_names_both(computer, kw, words):
    with pytest.raises(ConfigError) as e:
        predict_latency(convnet(), computer, **kw)
    for w in words:
        assert w in str(e.value)


def test_roofline_responds_to_precision_threads_and_depthwise():
    net = convnet()
    fp16 = predict_latency(net, "jetson-orin-nano", runtime="tensorrt", precision="fp16")
    int8 = predict_latency(net, "jetson-orin-nano", runtime="tensorrt", precision="int8")
    assert int8.seconds < fp16.seconds and fp16.method == "roofline"
    one = predict_latency(net, "raspberry-pi-4", runtime="onnxruntime", threads=1)
    four = predict_latency(net, "raspberry-pi-4", runtime="onnxruntime", threads=4)
    assert one.seconds > 1.5 * four.seconds
    # per MAC, depthwise layers run slower than dense ones
    dw = predict_latency(convnet(depthwise=True), "jetson-orin-nano", runtime="tensorrt")
    assert dw.seconds / dw.macs > fp16.seconds / fp16.macs
    # MACs as counted by the graph: 3x3 convs, BN and ReLU fused (no time of their own)
    want = 64 * 64 * 9 * (32 * 3 + 32 * 32 + 32 * 32)
    assert sum(n[2] > 0 for n in fp16.per_node) == 3
    assert fp16.macs >= want
    dev = fa.compute.device("jetson-orin-nano")
    assert fp16.energy_j == pytest.approx(fp16.seconds * (dev.active_w - dev.idle_w))
    assert fp16.band[0] < fp16.seconds < fp16.band[1]


def test_energy_on_a_cpu_draws_the_share_of_the_cores_its_threads_use():
    """busy_w is the board with every core busy: one thread of four draws a quarter of the
    busy power above idle; a GPU deployment draws all of it."""
    net = convnet()
    pi = fa.compute.device("raspberry-pi-4")
    above = pi.active_w - pi.idle_w
    one = predict_latency(net, "raspberry-pi-4", runtime="tflite")          # TF Lite: 1 thread
    two = predict_latency(net, "raspberry-pi-4", runtime="onnxruntime", threads=2)
    every = predict_latency(net, "raspberry-pi-4", runtime="onnxruntime")   # all four cores
    assert one.threads == 1 and every.threads is None
    assert one.energy_j == pytest.approx(one.seconds * above / 4)
    assert two.energy_j == pytest.approx(two.seconds * above / 2)
    assert every.energy_j == pytest.approx(every.seconds * above)
    orin = fa.compute.device("jetson-orin-nano")
    cpu = predict_latency(net, "jetson-orin-nano", runtime="tflite")
    assert cpu.energy_j == pytest.approx(
        cpu.seconds * (orin.active_w - orin.idle_w) / orin.unit("cpu").cores)


def test_a_bare_mac_count_falls_back_to_the_old_rule_with_a_warning():
    pi = fa.compute.device("raspberry-pi-4")
    with pytest.warns(LatencyFallbackWarning, match="MAC-count rule"):
        p = predict_latency(5.26e8, "raspberry-pi-4")
    assert p.method == "macs" and p.seconds == pytest.approx(pi.overhead_s + 5.26e8 / pi.macs_per_s)


def _rows(held_latency_s):
    """Synthetic rows: tuning rows generated by the roofline with known efficiencies,
    held-out rows with whatever latency the caller gives."""
    truth = {"targets": {"cpu": {"mem": 0.3, "dispatch_s": 3e-5, "overhead_s": 2e-3,
                                 "dwconv": 0.05}},
             "groups": {"onnxruntime/cpu/fp32": {"scale": 0.4}, "ncnn/cpu/fp32": {"scale": 0.8}}}
    from pytest_flockai.compute.graph import analyze
    rows = []
    for i, (side, dw) in enumerate([(s, d) for s in (64, 96, 128, 160) for d in (False, True)]):
        cost = analyze(convnet(depthwise=dw, side=side))
        for j, (rt, comp) in enumerate([("onnxruntime", "raspberry-pi-4"),
                                        ("ncnn", "raspberry-pi-5")]):
            r = published.Row(f"{i}{j}", "s", "tuning", comp, rt, "cpu", "fp32", "n", str(side),
                              1.0, cost)
            secs = published.predict_row(r, truth)
            rows.append(published.Row(r.row_id, "s", "tuning", comp, rt, "cpu", "fp32", "n",
                                      str(side), secs, cost))
    rows += [published.Row(f"h{k}", "h", "heldout", "raspberry-pi-4", "onnxruntime", "cpu",
                           "fp32", "n", "64", held_latency_s, rows[0].cost) for k in range(3)]
    return rows


def test_tuning_reads_the_tuning_half_only_and_recovers_known_efficiencies():
    a = tuning.tune(_rows(0.001))
    b = tuning.tune(_rows(50.0))                      # held-out rows moved 50000x
    assert a["targets"] == b["targets"] and a["groups"] == b["groups"]
    s = published.summary(_rows(0.001), a)
    assert s["tuning"]["all"]["median_abs_ln"] < math.log(1.05)
    assert set(s) == {"tuning", "heldout"}
    # the vectorised fit and the predictor agree on the fitted table
    r = _rows(1.0)[0]
    dep = runtimes.resolve(fa.compute.device(r.computer), r.runtime, r.precision, r.target)
    assert params_for(a, dep)["tuned"]


def test_leave_one_source_out_reads_the_tuning_half_only():
    """tuning.loso fits without each tuning source in turn: the held-out rows (moved 50000x)
    change nothing, rows generated by the model itself come back within 5 %, and a source
    whose rows are 3x off shows it while the others do not."""
    rows = [dataclasses.replace(r, source_id="a" if (i // 4) % 2 else "b") if r.half == "tuning" else r
            for i, r in enumerate(_rows(0.001))]
    rule = {"rule": {"scale": "runtime", "dispatch": "prior"}}
    a = tuning.loso(rows, rule)
    assert a == tuning.loso([r if r.half == "tuning" else dataclasses.replace(r, latency_s=50.0)
                             for r in rows], rule)
    assert set(a["per_source"]) == {"a", "b"} and a["median_of_sources"] < math.log(1.05)
    off = [dataclasses.replace(r, latency_s=3 * r.latency_s) if r.source_id == "a" else r
           for r in rows]
    b = tuning.loso(off, rule)
    assert b["per_source"]["a"]["median_abs_ln"] > math.log(2.0)
    assert b["pooled_mean"] > a["pooled_mean"]


def test_tasks_fly_with_the_latency_of_their_deployment(tmp_path):
    path = tmp_path / "net.onnx"
    onnx.save(convnet(side=64), path)
    model = fa.ml.OnnxModel(path)

    def fly(**kw):
        task = fa.Task(model, period_s=1.0, device="jetson-orin-nano", alert="result", **kw)
        r = fa.ml.TaskRunner(task).bind(0)
        r.on_frame(0.0, np.zeros((64, 64, 3), np.uint8))
        r.advance(10.0)
        return r.kpis()["inference_latency_p50_s"]

    want = predict_latency(path, "jetson-orin-nano", runtime="onnxruntime", target="cpu")
    assert fly(runtime="onnxruntime", target="cpu") == pytest.approx(want.seconds)
    assert fly(runtime="tensorrt", precision="int8") < fly(runtime="onnxruntime", target="cpu")
    with pytest.raises(ConfigError, match="edgetpu.*jetson-orin-nano"):
        fa.Task(model, device="jetson-orin-nano", runtime="edgetpu")
    with pytest.raises(ConfigError, match="precision = 'fp9'"):
        fa.Task(model, precision="fp9")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fa.Task(model, device="jetson-orin-nano", runtime="tensorrt")      # no fallback warning
    with pytest.warns(LatencyFallbackWarning):
        fa.Task(fa.ml.PythonModel(lambda f: 0, macs=1e6), runtime="tensorrt", device="ground-gpu")


def test_the_drones_blueprint_sets_the_default_runtime_of_its_tasks(tmp_path):
    path = tmp_path / "net.onnx"
    onnx.save(convnet(side=64), path)
    model = fa.ml.OnnxModel(path)
    drone = fa.drone("generic-hexa-680", runtime="tensorrt", precision="int8")
    assert drone.runtime == "tensorrt" and drone.to_dict()["precision"] == "int8"
    r = fa.Mission(drone, fa.pilots.Hover(altitude=3.0, duration=3.0), seed=0,
                   tasks=[fa.Task(model, period_s=1.0, alert="result")]).run()
    want = predict_latency(model, "jetson-orin-nano", runtime="tensorrt", precision="int8",
                           input_shape=(1, 3, 64, 64))
    assert r.kpis["inference_latency_p50_s"] == pytest.approx(want.seconds)
    with pytest.raises(ConfigError, match="runtime = 'tensorrtt'"):
        fa.drone("generic-hexa-680", runtime="tensorrtt")
    with pytest.raises(ConfigError, match="tensorrt.*raspberry-pi-4"):
        fa.Mission(fa.drone("dji-mavic-2-pro", device="raspberry-pi-4", runtime="tensorrt"),
                   fa.pilots.Hover(altitude=3.0, duration=3.0), tasks=[fa.Task(model)]).run()


def test_compare_models_gives_the_latency_per_runtime(tmp_path):
    """The paper's Q4 with runtimes: one row per model and runtime, the layer model for the
    ONNX detector, the MAC-count rule for a model given by its MACs."""
    from labelled_sets import make_set, perfect_model

    path, sc = make_set(tmp_path / "set", "yolo-images-labels", n=4)
    det = fa.ml.shipped("detector")
    stated = fa.ml.PythonModel(perfect_model(sc), macs=3e9, name="stated")
    df = fa.ml.compare_models({"det": det, "stated": stated}, path, device="jetson-orin-nano",
                              runtimes=["tensorrt", ("tensorrt", "int8"), "onnxruntime"])
    assert len(df) == 6 and set(df["runtime"]) == {"tensorrt", "onnxruntime"}
    d = df[df.model == "det"].set_index(["runtime", "runtime_precision"])["latency_s"]
    assert d[("tensorrt", "int8")] < d[("tensorrt", "fp16")] < d[("onnxruntime", "fp32")]
    s = df[df.model == "stated"]
    assert set(s["latency_model"]) == {"macs"} and s["latency_s"].nunique() == 1
    assert set(df[df.model == "det"]["latency_model"]) == {"roofline"}
    with pytest.raises(ConfigError, match="edgetpu"):
        fa.ml.compare_models({"det": det}, path, device="jetson-orin-nano", runtimes=["edgetpu"])


def test_fleet_offload_times_the_ground_inference_with_the_layer_model(tmp_path):
    path = tmp_path / "net.onnx"
    onnx.save(convnet(side=64), path)
    off = fa.fleet.Offload(model=path, runtime="tensorrt", precision="fp16")
    want = predict_latency(path, "ground-gpu", runtime="tensorrt", precision="fp16")
    assert off.compute_s == pytest.approx(want.seconds) and off.macs == want.macs
    assert off.to_dict()["prediction"]["runtime"] == "tensorrt"
    plain = fa.fleet.Offload(macs=8.7e9)          # a MAC count: the ground GPU's MAC rule
    gpu = fa.compute.device("ground-gpu")
    assert plain.compute_s == pytest.approx(gpu.overhead_s + 8.7e9 / gpu.macs_per_s)
    with pytest.raises(ConfigError, match="edgetpu.*ground-gpu"):
        fa.fleet.Offload(model=path, runtime="edgetpu")
    with pytest.raises(ConfigError, match="runtime = 'trt'"):
        fa.fleet.Offload(runtime="trt")


#: ``added`` months (latency_sources.csv) of the sources latency_efficiencies.json was tuned on
TUNED_ON = {"2026-11", "2026-11-27", "2026-11-28", "2026-12-06"}


@pytest.mark.slow
def test_the_stored_efficiencies_are_what_the_tuning_procedure_gives():
    """latency_efficiencies.json is the output of benchmarks/latency_tune.py on the data in
    the repository (tuning half only), and the validation runs on every row it was tuned with.
    Sources added to ``latency_sources.csv`` after the last tuning (``added`` not in
    ``TUNED_ON``) wait for the next run of the tuning script, which adds their month here."""
    rows, skipped = published.load_rows()
    assert len(rows) >= 80 and not skipped
    rows = [r for r in rows if r.added in TUNED_ON]
    assert {r.half for r in rows} == {"tuning", "heldout"}
    stored = fa.compute.predict.efficiencies()
    again = tuning.tune(rows)
    for t, p in again["targets"].items():
        for k, v in p.items():
            assert stored["targets"][t][k] == pytest.approx(v, rel=1e-6), (t, k)
    assert {g: v["scale"] for g, v in stored["groups"].items()} == pytest.approx(
        {g: v["scale"] for g, v in again["groups"].items()}, rel=1e-6)
    assert stored["rows"]["tuning"] == sum(r.half == "tuning" for r in rows)
    assert stored["rows"]["heldout"] == sum(r.half == "heldout" for r in rows)
    s = published.summary(rows, stored)
    assert stored["validation"]["heldout"]["n"] == s["heldout"]["all"]["n"]
    assert s["heldout"]["all"]["median_abs_ln"] == pytest.approx(
        stored["validation"]["heldout"]["median_abs_ln"])


def _conv(name, cin, cout, k, stride, side):
    from pytest_flockai.compute.graph import NodeCost
    out_side = side // stride
    w = cout * cin * k * k
    return NodeCost(name, "Conv", "conv", w * out_side ** 2, w + cout, cin * side ** 2,
                    cout * out_side ** 2)


def test_winograd_eligibility_is_read_from_the_node_counts():
    from pytest_flockai.compute.predict import winograd_3x3
    assert winograd_3x3(_conv("a", 64, 64, 3, 1, 56))          # VGG/ResNet body convolution
    assert not winograd_3x3(_conv("b", 64, 128, 3, 2, 56))     # stride 2
    assert not winograd_3x3(_conv("c", 64, 256, 1, 1, 56))     # 1x1
    assert not winograd_3x3(_conv("d", 3, 32, 3, 1, 224))      # too few input channels
    assert not winograd_3x3(_conv("e", 64, 64, 5, 1, 56))      # 5x5


def test_a_gated_activation_is_its_own_pass_where_the_runtime_cannot_fuse_it():
    from dataclasses import replace

    from pytest_flockai.compute.graph import NodeCost
    from pytest_flockai.compute.predict import dispatched
    conv = _conv("c", 64, 64, 3, 1, 56)
    n = conv.out_elems
    silu = [conv, NodeCost("s", "Sigmoid", "elementwise", n, 0, n, n, "c"),
            NodeCost("m", "Mul", "elementwise", n, 0, 2 * n, n, "c")]
    hswish = [conv, replace(silu[1], op_type="HardSigmoid"), silu[2]]
    assert [x.name for x in dispatched(silu, "tensorrt")] == ["c"]
    extra = dispatched(silu, "ncnn")            # ncnn has no Swish activation in its Conv
    assert [x.name for x in extra] == ["c", "m"] and extra[1].in_elems == n
    assert [x.name for x in dispatched(hswish, "ncnn")] == ["c"]      # hard-swish fused
    assert [x.name for x in dispatched(silu, "onnxruntime")] == ["c", "m"]


def test_memory_time_uses_the_measured_stream_bandwidth_where_published():
    from pytest_flockai.compute.predict import STREAM_OF_PEAK, stream_gbs
    pi4, orin = fa.compute.device("raspberry-pi-4"), fa.compute.device("jetson-orin-nano")
    assert pi4.stream_gbs == pytest.approx(5.56) and stream_gbs(pi4) == pytest.approx(5.56)
    assert orin.stream_gbs == 0.0
    assert stream_gbs(orin) == pytest.approx(STREAM_OF_PEAK * orin.bandwidth_gbs)
