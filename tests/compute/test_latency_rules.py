"""Rules of the latency model that come from runtime behaviour and from the tuning half:
eager PyTorch runs activations as passes of their own, a deployment without tuning rows
takes the rule the tuning file records, the datasheets carry every figure a Device needs,
and the validation script's verdict follows the two criteria of the held-out target."""

import copy
import dataclasses
import sys
import tomllib
from pathlib import Path

import pytest

from pytest_flockai.compute import datasheets, runtimes
from pytest_flockai.compute.devices import DEVICES
from pytest_flockai.compute.graph import NetworkCost, NodeCost
from pytest_flockai.compute.predict import (
    dispatched,
    efficiencies,
    params_for,
    predict_latency,
    roofline,
)
from pytest_flockai.errors import ConfigError

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import latency_validation  # noqa: E402


def conv_relu(n=4, side=56, ch=64) -> NetworkCost:
    """n x (3x3 Conv, ReLU fused into it) on a side x side x ch activation."""
    el = side * side * ch
    nodes = []
    for i in range(n):
        nodes.append(NodeCost(f"c{i}", "Conv", "conv", el * ch * 9, ch * ch * 9, el, el, None))
        nodes.append(NodeCost(f"r{i}", "Relu", "elementwise", el, 0, el, el, f"c{i}"))
    return NetworkCost(tuple(nodes), "conv-relu")


def test_eager_pytorch_runs_each_activation_as_its_own_pass():
    cost = conv_relu()
    assert len(dispatched(cost.nodes, "tensorrt")) == 4
    assert len(dispatched(cost.nodes, "onnxruntime")) == 4
    eager = dispatched(cost.nodes, "pytorch")
    assert len(eager) == 8 and sum(n.op_type == "Relu" for n in eager) == 4
    dev = DEVICES["jetson-orin-nano"]
    pt = predict_latency(cost, dev, runtime="pytorch", precision="fp16")
    assert len(pt.per_node) == 8 and sum(k == "elementwise" for _, k, _, _ in pt.per_node) == 4


def test_untuned_deployment_follows_the_recorded_rule():
    dev = DEVICES["jetson-nano-10w"]
    dep = runtimes.resolve(dev, "pytorch", "fp16")
    table = {"groups": {"pytorch/gpu/fp32": {"scale": 4.0}, "tensorrt/gpu/fp16": {"scale": 1.0},
                        "tensorrt/gpu/fp32": {"scale": 2.0}, "ncnn/cpu/fp32": {"scale": 9.0}},
             "dispatch": {"tensorrt/gpu": {"factor": 0.5}, "ncnn/gpu": {"factor": 2.5},
                          "ncnn/cpu": {"factor": 9.0}}}
    by_runtime = params_for({**table, "fallback": {"rule": {"scale": "runtime",
                                                            "dispatch": "prior"}}}, dep)
    by_target = params_for({**table, "fallback": {"rule": {"scale": "target",
                                                           "dispatch": "target"}}}, dep)
    assert by_runtime["scale"] == 4.0                  # PyTorch's own scale at fp32
    assert by_target["scale"] == 2.0                   # median of the GPU groups 4, 1, 2
    ort = runtimes.resolve(dev, "onnxruntime", "fp32", "gpu")
    base = params_for({}, ort)["dispatch_s"]
    prior = params_for({**table, "fallback": {"rule": {"scale": "target",
                                                       "dispatch": "prior"}}}, ort)
    target = params_for({**table, "fallback": {"rule": {"scale": "target",
                                                        "dispatch": "target"}}}, ort)
    assert prior["dispatch_s"] == pytest.approx(base)
    assert target["dispatch_s"] == pytest.approx(base * 1.5)   # median of 0.5 and 2.5 (GPU)


def test_datasheet_without_a_figure_is_refused_naming_it():
    with datasheets.COMPUTERS.open("rb") as fh:
        t = tomllib.load(fh)["computers"]["jetson-nano-10w"]
    dev = datasheets.from_datasheet("jetson-nano-10w", t)
    assert dev == DEVICES["jetson-nano-10w"]
    assert dev.macs_per_s == t["mac_rule"]["macs_per_s"] and dev.idle_w == t["power"]["idle_w"]
    for table, key in (("mac_rule", "macs_per_s"), ("power", "busy_w"), ("", "memory_mb")):
        bad = copy.deepcopy(t)
        del (bad[table] if table else bad)[key]
        with pytest.raises(ConfigError, match=f"jetson-nano-10w.*{key}"):
            datasheets.from_datasheet("jetson-nano-10w", bad)


def test_every_estimated_figure_says_so():
    with datasheets.COMPUTERS.open("rb") as fh:
        comps = tomllib.load(fh)["computers"]
    for name, t in comps.items():
        for key in ("macs_per_s", "overhead_s"):
            assert t["mac_rule"][f"{key}_source"].startswith("estimate"), (name, key)
        for key in ("idle_w", "busy_w"):
            assert key in t["power"] and t["power"][f"{key}_source"], (name, key)


def _stats(n, med, worst, within):
    return {"n": n, "median_ratio": 1.0, "median_abs_ln": med, "worst_ratio": worst,
            "within_2x": within}


def test_verdict_needs_both_criteria_and_eight_rows():
    s = {"heldout": {"computer": {"a": _stats(10, 0.20, 1.9, 10), "b": _stats(10, 0.25, 1.5, 10),
                                  "c": _stats(10, 0.10, 2.3, 9), "d": _stats(7, 0.1, 1.1, 7)}}}
    v = {x["computer"]: x["verdict"] for x in latency_validation.verdicts(s)}
    assert v == {"a": "PASS", "b": "FAIL", "c": "FAIL"}
    text = "\n".join(latency_validation.verdict_lines(s))
    assert "1 of 3 computers" in text


def test_openvino_and_ncnn_run_fp32_models_in_fp16_only_on_armv82_cores():
    """Pi 5 (Cortex-A76, Armv8.2 FP16): ncnn and OpenVINO compute an fp32 request at the fp16
    rate with 2-byte elements; ONNX Runtime does not. Pi 4 (Cortex-A72, Armv8.0): all fp32."""
    pi5, pi4 = DEVICES["raspberry-pi-5"], DEVICES["raspberry-pi-4"]
    for name in ("openvino", "ncnn"):
        dep = runtimes.resolve(pi5, name, "fp32", "cpu")
        assert runtimes.compute_precision(dep, pi5.unit("cpu")) == ("fp16", 2.0)
        assert runtimes.peak_macs(dep, pi5.unit("cpu")) == pi5.unit("cpu").peak_macs("fp16")
        dep4 = runtimes.resolve(pi4, name, "fp32", "cpu")
        assert runtimes.compute_precision(dep4, pi4.unit("cpu")) == ("fp32", 4.0)
    ort = runtimes.resolve(pi5, "onnxruntime", "fp32", "cpu")
    assert runtimes.compute_precision(ort, pi5.unit("cpu")) == ("fp32", 4.0)


def test_eager_pytorch_fp16_runs_at_the_fp32_rate_without_tensor_cores():
    """PyTorch's cuDNN convolutions compute half data in float: on the Nano's Maxwell GPU
    (no tensor cores) fp16 keeps 2-byte storage but the fp32 rate; TensorRT fp16 gets the
    fp16 rate; on the Orin (tensor cores) PyTorch fp16 is not slowed to fp32."""
    nano, orin = DEVICES["jetson-nano-10w"], DEVICES["jetson-orin-nano"]
    gpu = nano.unit("gpu")
    pt = runtimes.resolve(nano, "pytorch", "fp16", "gpu")
    assert runtimes.compute_precision(pt, gpu) == ("fp32", 2.0)
    assert runtimes.peak_macs(pt, gpu) == gpu.peak_macs("fp32") < gpu.peak_macs("fp16")
    trt = runtimes.resolve(nano, "tensorrt", "fp16", "gpu")
    assert runtimes.compute_precision(trt, gpu) == ("fp16", 2.0)
    pt_orin = runtimes.resolve(orin, "pytorch", "fp16", "gpu")
    assert runtimes.compute_precision(pt_orin, orin.unit("gpu")) == ("fp16", 2.0)


def test_the_band_falls_back_to_the_computer_before_every_computer():
    """A computer/runtime pair with too few held-out rows takes the range of that computer's
    rows on the same unit, and only without those the range of every computer's."""
    from pytest_flockai.compute import predict
    pi4 = DEVICES["raspberry-pi-4"]
    dep = runtimes.resolve(pi4, "onnxruntime", "fp32", "cpu")
    n = predict.MIN_BAND_ROWS
    bands = {"raspberry-pi-4/onnxruntime": {"min": 0.9, "max": 1.1, "n": n - 1},
             "raspberry-pi-4/*/cpu": {"min": 0.7, "max": 1.8, "n": n},
             "*/cpu": {"min": 0.1, "max": 8.0, "n": 10 * n}}
    assert predict._band({"bands": bands}, pi4, dep, 1.0) == (0.7, 1.8)
    bands["raspberry-pi-4/onnxruntime"]["n"] = n            # enough rows of its own
    assert predict._band({"bands": bands}, pi4, dep, 1.0) == (0.9, 1.1)
    del bands["raspberry-pi-4/onnxruntime"]
    bands["raspberry-pi-4/*/cpu"]["n"] = n - 1              # too few on this computer too
    assert predict._band({"bands": bands}, pi4, dep, 2.0) == (0.2, 16.0)
    assert predict._band({}, pi4, dep, 1.0) == (0.5, 2.0)    # untuned: the 2x


def test_a_band_needs_rows_of_two_publishers():
    """Rows of one publisher (two revisions of one maker's guide) say how that publisher
    agrees with itself: such a pair takes its computer's band; the tuned table records the
    publishers of each band, read from latency_sources.csv."""
    from pytest_flockai.compute import predict, published
    pi5 = DEVICES["raspberry-pi-5"]
    dep = runtimes.resolve(pi5, "onnxruntime", "fp32", "cpu")
    n, k = predict.MIN_BAND_ROWS, predict.MIN_BAND_SOURCES
    bands = {"raspberry-pi-5/onnxruntime": {"min": 0.92, "max": 0.99, "n": n, "sources": k - 1},
             "raspberry-pi-5/*/cpu": {"min": 0.3, "max": 8.0, "n": 4 * n, "sources": k}}
    assert predict._band({"bands": bands}, pi5, dep, 1.0) == (0.3, 8.0)
    bands["raspberry-pi-5/onnxruntime"]["sources"] = k
    assert predict._band({"bands": bands}, pi5, dep, 1.0) == (0.92, 0.99)
    rows, _ = published.load_rows()
    assert {r.publisher for r in rows if r.source_id.startswith("ultralytics-")} == {"Ultralytics"}
    assert {r.publisher for r in rows if r.source_id.startswith("krai-")} == {"Krai"}
    table = predict.efficiencies()
    held = [r for r in rows if r.half == "heldout"]
    for key, b in table["bands"].items():
        if key.startswith("untuned/"):      # leave-one-computer-out: test_own_computer.py
            continue
        comp, _, rest = key.partition("/")
        mine = [r for r in held if comp in ("*", r.computer) and (
            rest == f"*/{r.target}" if rest.startswith("*/") else
            rest == r.target if comp == "*" else rest == r.runtime)]
        assert b["n"] == len(mine) and b["sources"] == len({r.publisher for r in mine}), key
        inv = 1.0 / published.ratios(mine, table)
        assert (b["min"], b["max"]) == pytest.approx((inv.min(), inv.max())), key


def test_a_band_of_many_rows_is_their_central_ninety_percent():
    """One doubtful row among many does not set the band; a few rows give their range."""
    from pytest_flockai.compute import predict, published
    many = [1.0] * 10 + [1.1] * 10 + [0.9] * 10 + [8.0]          # 31 rows, one far out
    b = published.band_of(many)
    assert (b["min"], b["max"], b["n"]) == (0.9, 8.0, 31)
    assert b["lo"] == pytest.approx(0.9) and b["hi"] == pytest.approx(1.1)
    few = published.band_of([0.5, 1.0, 3.0])
    assert few["lo"] == 0.5 and few["hi"] == 3.0 and predict.BAND_QUANTILE_ROWS > 3
    pi4 = DEVICES["raspberry-pi-4"]
    dep = runtimes.resolve(pi4, "onnxruntime", "fp32", "cpu")
    table = {"bands": {"*/cpu": {**b, "sources": 5}}}
    assert predict._band(table, pi4, dep, 2.0) == pytest.approx((1.8, 2.2))


def test_a_row_measured_at_another_cpu_clock_is_predicted_at_that_clock():
    """The 2022 ncnn Raspberry Pi 4 section ran at 1.5 GHz (its heading): its rows carry
    cpu_clock_ghz and are predicted on a CPU whose clock and peaks are scaled to it."""
    from pytest_flockai.compute import published
    pi4 = DEVICES["raspberry-pi-4"]
    slow = published.at_cpu_clock(pi4, 1.5)
    assert slow.unit("cpu").clock_ghz == 1.5 and published.at_cpu_clock(pi4, None) is pi4
    assert slow.unit("cpu").peak_macs("fp32") == pytest.approx(
        pi4.unit("cpu").peak_macs("fp32") * 1.5 / pi4.unit("cpu").clock_ghz)
    rows, _ = published.load_rows()
    clocked = [r for r in rows if r.cpu_clock_ghz]
    # sources whose document states a clock other than the datasheet's (their heading, the
    # MLPerf system description's host_processor_frequency, the OpenCV Zoo's board specs):
    # so far, Raspberry Pi 4s at the 1.5 GHz of the boards made before 2020
    assert clocked and all(r.computer == "raspberry-pi-4" and r.cpu_clock_ghz == 1.5
                           for r in clocked)
    assert {"ncnn-benchncnn-rpi4-1500mhz-2022", "opencv-zoo-benchmark"} <= {
        r.source_id for r in clocked}
    r = next(r for r in clocked if r.source_id == "ncnn-benchncnn-rpi4-1500mhz-2022")
    table = {}          # the untuned priors: the clock alone makes the difference
    at_sheet = published.predict_row(dataclasses.replace(r, cpu_clock_ghz=None), table)
    assert published.predict_row(r, table) > at_sheet


def test_a_row_run_on_fewer_threads_is_predicted_on_that_many_cores(tmp_path):
    """Ultralytics' TFLite rows ran on one thread (its AutoBackend builds the TFLite
    Interpreter without num_threads; TFLite's XNNPACK delegate then has no thread pool): they
    carry threads = 1 and are predicted on one core; a thread count the computer does not
    have is refused naming the row, the field and what is allowed."""
    from pytest_flockai.compute import published
    rows, _ = published.load_rows()
    one = [r for r in rows if r.threads == 1]
    assert one and all(r.runtime == "tflite" and r.source_id.startswith("ultralytics-")
                       for r in one)
    assert {r.computer for r in one} >= {"raspberry-pi-5", "jetson-orin-nx-16gb"}
    r = next(x for x in one if x.computer == "raspberry-pi-5")
    table = {}
    four = published.predict_row(dataclasses.replace(r, threads=4), table)
    assert published.predict_row(r, table) > 1.5 * four
    assert r.deployment.threads == 1
    # TF Lite's own default is one thread; the other runtimes' is every core (None)
    assert published.predict_row(dataclasses.replace(r, threads=None), table) == \
        published.predict_row(r, table)
    pi5 = DEVICES["raspberry-pi-5"]
    assert runtimes.resolve(pi5, "tflite", "fp32").threads == 1
    assert runtimes.resolve(pi5, "tflite", "fp32", threads=4).threads == 4
    assert runtimes.resolve(pi5, "onnxruntime", "fp32").threads is None
    assert {x.threads for x in rows if x.source_id == "nobuotsukamoto-tflite-raspi"} == {4}
    src = published.TABLE.read_text(encoding="utf-8").splitlines()
    head, first = src[0], next(line for line in src[1:] if ",raspberry-pi-4," in line)
    for bad in ("5", "x", "0"):
        fields = first.rsplit(",", 1)[0]
        (tmp_path / "t.csv").write_text(f"{head}\n{fields},{bad}\n", encoding="utf-8")
        with pytest.raises(ConfigError, match=r"threads = '.*' is not allowed.*1\.\.4"):
            published.load_rows(tmp_path / "t.csv")


def test_cpu_threads_add_at_the_tuned_parallel_efficiency():
    """n CPU threads run as 1 + (n - 1) * parallel threads' worth of one core's peak: one
    thread is one core whatever the efficiency, every thread at parallel = 1, and a GPU or
    NPU is not touched. The stored table's figure lies between the bounds, below 1."""
    from pytest_flockai.compute.predict import efficiencies
    from pytest_flockai.compute.runtimes import thread_share
    pi5 = DEVICES["raspberry-pi-5"]
    cpu = pi5.unit("cpu")
    one = runtimes.resolve(pi5, "onnxruntime", "fp32", threads=1)
    four = runtimes.resolve(pi5, "onnxruntime", "fp32")
    assert thread_share(one, cpu, 0.5) == 1.0
    assert thread_share(four, cpu, 1.0) == 1.0
    assert thread_share(four, cpu, 0.5) == pytest.approx((1 + 3 * 0.5) / 4)
    nano = DEVICES["jetson-nano-10w"]
    gpu_dep = runtimes.resolve(nano, "tensorrt", "fp16")
    assert thread_share(gpu_dep, nano.unit("gpu"), 0.5) == 1.0
    par = efficiencies()["targets"]["cpu"]["parallel"]
    assert 0.2 <= par < 1.0
    cost = conv_relu(n=2)
    t = {"targets": {"cpu": {"parallel": 0.5}}}
    a = roofline(cost, pi5, one, params_for(t, one))[0]
    b = roofline(cost, pi5, four, params_for(t, four))[0]
    assert 2.0 < a / b < 2.5            # 2.5 threads' worth, the memory side unchanged


def test_parameters_beyond_the_edge_tpus_memory_stream_over_its_link():
    """The Edge TPU caches a network's parameters in its 8 MB of on-chip memory in the
    network's order; the rest stream from the host over its PCIe link at every inference, so
    a large network pays its parameter bytes over the link, and a small one does not."""
    from pytest_flockai.compute import published, tuning
    from pytest_flockai.compute.runtimes import param_stream
    mb = 2 ** 20
    assert param_stream(3 * mb, 0.0, 8 * mb) == (0.0, 3 * mb)           # fits
    assert param_stream(3 * mb, 7 * mb, 8 * mb) == (2 * mb, 8 * mb)     # 1 MB fits
    assert param_stream(3 * mb, 8 * mb, 8 * mb) == (3 * mb, 8 * mb)     # full: all streams
    coral = DEVICES["coral-dev-board"]
    tpu = coral.unit("npu")
    assert tpu.cache_mb == 8.0 and tpu.link_gbs == 0.5
    vgg = published.network_cost("vgg16", "224")
    mobilenet = published.network_cost("mobilenet_v2", "224")
    for cost, streams in ((vgg, True), (mobilenet, False)):
        p = predict_latency(cost, coral, runtime="edgetpu")
        no_link = dataclasses.replace(coral, units=(dataclasses.replace(tpu, link_gbs=0.0),))
        q = predict_latency(cost, no_link, runtime="edgetpu")
        weights = cost.weight_elems            # int8: one byte each
        if streams:                            # 138 M parameters: 130 MB over 0.5 GB/s
            assert p.seconds - q.seconds >= 0.9 * (weights - 8 * mb) / 0.5e9
        else:                                  # 3.5 M parameters: all on chip
            assert p.seconds == pytest.approx(q.seconds)
    # the tuner's fast path computes the same seconds as the roofline (one model, two codes)
    table = efficiencies()
    rows, _ = published.load_rows()
    row = next(r for r in rows if r.computer == "coral-dev-board" and r.network == "vgg16")
    prm = params_for(table, row.deployment)
    fast = tuning._Compiled(row).seconds(prm, prm["scale"], 1.0)
    slow, _ = roofline(row.cost, row.device, row.deployment, prm)
    assert fast == pytest.approx(slow, rel=1e-9)


def test_a_view_costs_a_dispatch_and_moves_no_data():
    """Reshape / Flatten / Squeeze / Unsqueeze alias their input's buffer: each adds its
    dispatch to the time, not a pass over its tensor; a Transpose (a copy) still moves it."""
    base = conv_relu(2, side=112)
    el = 112 * 112 * 64

    def with_(op):
        extra = NodeCost("v", op, "data", 0, 0, el, el, None)
        return NetworkCost(base.nodes + (extra,), op)

    dev = DEVICES["raspberry-pi-4"]
    dep = runtimes.resolve(dev, "onnxruntime")
    prm = params_for(efficiencies(), dep)
    t0 = roofline(base, dev, dep, prm)[0]
    one_dispatch = prm["dispatch_s"] / dev.unit("cpu").clock_ghz
    for op in ("Reshape", "Flatten", "Squeeze", "Unsqueeze"):
        (view,) = [n for n in dispatched(with_(op).nodes, "onnxruntime") if n.name == "v"]
        assert view.in_elems == view.out_elems == 0
        assert roofline(with_(op), dev, dep, prm)[0] == pytest.approx(t0 + one_dispatch)
    t, per = roofline(with_("Transpose"), dev, dep, prm)
    (copy,) = [p for p in per if p[0] == "v"]
    assert copy[3] == "memory" and t - t0 > 10 * one_dispatch     # a pass over its tensor


def test_the_fit_keeps_weights_at_half_the_sustained_bandwidth_or_more():
    """Weights are one sequential read per layer: the stored table was fitted under the
    tuner's current floor (a table left from before a change of the bounds fails here)."""
    from pytest_flockai.compute.tuning import BOUNDS
    lo, hi = BOUNDS["mem_weights"]
    for target, figs in efficiencies()["targets"].items():
        assert lo - 1e-9 <= figs["mem_weights"] <= hi, target
