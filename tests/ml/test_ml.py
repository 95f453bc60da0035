"""ML deployment: MAC counting, models on ONNX Runtime, templates, tasks and the runner."""

import math
import warnings

import numpy as np
import onnx
import pytest
from onnx import TensorProto, helper, numpy_helper

from pytest_flockai.comm import Link
from pytest_flockai.compute.devices import device
from pytest_flockai.errors import ConfigError
from pytest_flockai.ml import (
    Counter,
    Detector,
    OnnxModel,
    OpenCVModel,
    PythonModel,
    Task,
    TaskRunner,
    count_macs,
    count_of,
    crowd_metrics,
)
from pytest_flockai.ml.jpeg import JPEG_MACS_PER_PIXEL, encode_jpeg

# -- helpers: small ONNX graphs built by hand ------------------------------------------
_RNG = np.random.default_rng(0)   # one stream shared by every _init call, in call order


def _init(name, shape, value=None, rng=_RNG):
    a = (np.full(shape, value, np.float32) if value is not None
         else rng.standard_normal(shape).astype(np.float32))
    return numpy_helper.from_array(a, name)


def _model(nodes, inputs, outputs, inits=(), opset=13):
    g = helper.make_graph(nodes, "t", inputs, outputs, list(inits))
    m = helper.make_model(g, opset_imports=[helper.make_opsetid("", opset)])
    m.ir_version = 8
    return m


def _vi(name, shape, t=TensorProto.FLOAT):
    return helper.make_tensor_value_info(name, t, shape)


def _save(m, tmp_path, name="m.onnx"):
    p = tmp_path / name
    onnx.save(m, str(p))
    return p


# -- MAC counting -----------------------------------------------------------------------
def test_macs_of_a_small_cnn_match_hand_count():
    nodes = [
        helper.make_node("Conv", ["x", "w1", "b1"], ["c1"], pads=[1, 1, 1, 1]),      # 1x4x8x8
        helper.make_node("Relu", ["c1"], ["r1"]),
        helper.make_node("MaxPool", ["r1"], ["p1"], kernel_shape=[2, 2], strides=[2, 2]),  # 1x4x4x4
        helper.make_node("Conv", ["p1", "wd"], ["d1"], pads=[1, 1, 1, 1], group=4),  # depthwise
        helper.make_node("ConvTranspose", ["d1", "wt"], ["u1"], strides=[2, 2]),      # 1x2x8x8
        helper.make_node("GlobalAveragePool", ["u1"], ["g1"]),                        # 1x2x1x1
        helper.make_node("Flatten", ["g1"], ["f1"]),                                  # 1x2
        helper.make_node("Gemm", ["f1", "wg", "bg"], ["y0"]),                         # 1x5
        helper.make_node("Add", ["y0", "k"], ["y"]),
    ]
    inits = [_init("w1", (4, 3, 3, 3)), _init("b1", (4,)), _init("wd", (4, 1, 3, 3)),
             _init("wt", (4, 2, 2, 2)), _init("wg", (2, 5)), _init("bg", (5,)), _init("k", (5,))]
    m = _model(nodes, [_vi("x", [1, 3, 8, 8])], [_vi("y", [1, 5])], inits)
    rep = count_macs(m)
    hand = {
        "Conv": 4 * 8 * 8 * (3 * 3 * 3) + 4 * 4 * 4 * (1 * 3 * 3),   # 6912 + 576
        "Relu": 4 * 8 * 8,                                           # 256
        "MaxPool": 4 * 4 * 4 * (2 * 2),                              # 256
        "ConvTranspose": (4 * 4 * 4) * (2 * 2 * 2),                  # in elements * Cout/g * k: 512
        "GlobalAveragePool": 2 * 8 * 8,                              # 128
        "Gemm": 1 * 5 * 2,                                           # M N K = 10
        "Add": 5,
    }
    assert rep.by_op == hand
    assert rep.macs == sum(hand.values()) == 8655
    assert rep.params == 108 + 4 + 36 + 32 + 10 + 5 + 5
    assert rep.uncounted == []


def test_macs_grouped_conv_strides_matmul_and_dynamic_dims():
    nodes = [helper.make_node("Conv", ["x", "w"], ["c"], group=2, strides=[2, 2]),  # 1x6x3x3
             helper.make_node("Reshape", ["c", "s"], ["r"]),                         # 1x6x9
             helper.make_node("MatMul", ["r", "wm"], ["y"])]                         # 1x6x7
    inits = [_init("w", (6, 2, 3, 3)), numpy_helper.from_array(np.array([1, 6, 9], np.int64), "s"),
             _init("wm", (9, 7))]
    m = _model(nodes, [_vi("x", ["N", 4, "H", "W"])], [_vi("y", None)], inits)
    rep = count_macs(m, {"x": [1, 4, 8, 8]})
    assert rep.by_op["Conv"] == 6 * 3 * 3 * (2 * 3 * 3)      # 972
    assert rep.by_op["MatMul"] == 6 * 7 * 9                  # 378
    assert rep.by_op.get("Reshape", 0) == 0
    assert rep.macs == 972 + 378
    assert rep.params == 6 * 2 * 9 + 63                      # int64 shape tensor not a parameter
    # Gemm with transposed B
    g = _model([helper.make_node("Gemm", ["a", "b"], ["y"], transB=1)],
               [_vi("a", [3, 16])], [_vi("y", [3, 10])], [_init("b", (10, 16))])
    assert count_macs(g).macs == 3 * 10 * 16


def test_count_macs_refuses_what_it_cannot_count_or_warns_when_allowed():
    # TopK is counted (in_elements comparisons); a custom-domain op is not: refused by name
    nodes = [helper.make_node("TopK", ["x", "k"], ["v", "i"]),
             helper.make_node("Mystery", ["v"], ["y"], name="head/mystery", domain="com.example")]
    m = _model(nodes, [_vi("x", [1, 10])], [_vi("y", None), _vi("i", None, TensorProto.INT64)],
               [numpy_helper.from_array(np.array([3], np.int64), "k")])
    m.opset_import.append(helper.make_opsetid("com.example", 1))
    with pytest.raises(ConfigError, match=r"Mystery head/mystery: custom domain 'com.example'"):
        count_macs(m)
    with pytest.warns(UserWarning, match=r"1 of 2 nodes .*\(50.0%\) are not counted"):
        rep = count_macs(m, allow_uncounted=True)
    assert rep.macs == 10 and rep.by_op == {"TopK": 10}
    assert rep.uncounted == ["Mystery head/mystery: custom domain 'com.example'"]


# -- OnnxModel ----------------------------------------------------------------------------
def _grey_mean_model(tmp_path, shape=(1, 3, 16, 16)):
    """1x1 conv averaging the 3 channels: output = mean of the preprocessed pixels."""
    m = _model([helper.make_node("Conv", ["x", "w"], ["y"])], [_vi("x", list(shape))],
               [_vi("y", None)], [_init("w", (1, 3, 1, 1), 1.0 / 3.0)])
    return _save(m, tmp_path, "mean.onnx")


def test_onnx_model_runs_real_inference_on_a_uint8_frame(tmp_path):
    import cv2
    model = OnnxModel(_grey_mean_model(tmp_path))
    assert model.macs == 16 * 16 * 3 and model.params == 3
    assert model.layout == "NCHW" and model.input_size == (16, 16)
    frame = np.random.default_rng(1).integers(0, 256, (24, 32, 3), dtype=np.uint8)
    out = model(frame)
    assert out.shape == (1, 16, 16)          # batch removed
    want = cv2.resize(frame, (16, 16), interpolation=cv2.INTER_AREA).astype(np.float32).mean(axis=2) / 255
    np.testing.assert_allclose(out[0], want, rtol=1e-5, atol=1e-5)
    # mean/std normalisation
    m2 = OnnxModel(_grey_mean_model(tmp_path), mean=0.5, std=0.25)
    np.testing.assert_allclose(m2(frame)[0], (want - 0.5) / 0.25, rtol=1e-4, atol=1e-4)


def test_onnx_model_nhwc_uint8_and_dynamic_size(tmp_path):
    # NHWC uint8 input, cast inside the graph: raw pixels reach the model
    nodes = [helper.make_node("Cast", ["x"], ["f"], to=TensorProto.FLOAT),
             helper.make_node("ReduceSum", ["f"], ["y"], keepdims=0)]
    m = _model(nodes, [_vi("x", [1, 8, 8, 3], TensorProto.UINT8)], [_vi("y", None)])
    model = OnnxModel(_save(m, tmp_path, "nhwc.onnx"))
    assert model.layout == "NHWC" and model.channels == 3
    frame = np.full((8, 8, 3), 2, np.uint8)
    assert float(model(frame)) == 8 * 8 * 3 * 2
    # dynamic H, W, one grey channel: fed at the frame's own size; MACs follow the frame
    d = _model([helper.make_node("Relu", ["x"], ["y"])], [_vi("x", ["N", 1, "H", "W"])],
               [_vi("y", None)])
    dyn = OnnxModel(_save(d, tmp_path, "dyn.onnx"))
    # macs is reported at the reference 240 x 320 frame and stays put
    assert dyn.input_size is None and dyn.macs == 240 * 320
    rgb = np.zeros((10, 20, 3), np.uint8)
    assert dyn(rgb).shape == (1, 10, 20)
    assert dyn.macs == 240 * 320 and dyn.macs_for(rgb) == 200
    assert dyn.macs_for(np.zeros((30, 40), np.uint8)) == 1200
    fixed = OnnxModel(_save(d, tmp_path, "dyn2.onnx"), input_size=(12, 16))
    assert fixed.macs == 12 * 16 and fixed(rgb).shape == (1, 12, 16)


def test_onnx_model_errors_name_the_path_and_the_reason(tmp_path):
    missing = tmp_path / "nope.onnx"
    with pytest.raises(ConfigError, match="nope.onnx"):
        OnnxModel(missing)
    bad = tmp_path / "corrupt.onnx"
    bad.write_bytes(b"\x08\x07this is not a protobuf model" * 10)
    with pytest.raises(ConfigError, match="corrupt.onnx.*not a valid ONNX"):
        OnnxModel(bad)
    rank2 = _model([helper.make_node("Relu", ["x"], ["y"])], [_vi("x", [1, 10])], [_vi("y", None)])
    with pytest.raises(ConfigError, match="rank 2"):
        OnnxModel(_save(rank2, tmp_path, "rank2.onnx"))
    ints = _model([helper.make_node("Identity", ["x"], ["y"])],
                  [_vi("x", [1, 3, 4, 4], TensorProto.INT64)], [_vi("y", None, TensorProto.INT64)])
    with pytest.raises(ConfigError, match="int64"):
        OnnxModel(_save(ints, tmp_path, "ints.onnx"))
    two = _model([helper.make_node("Add", ["a", "b"], ["y"])],
                 [_vi("a", [1, 3, 4, 4]), _vi("b", [1, 3, 4, 4])], [_vi("y", None)])
    with pytest.raises(ConfigError, match="2 inputs"):
        OnnxModel(_save(two, tmp_path, "two.onnx"))
    five = _model([helper.make_node("Relu", ["x"], ["y"])], [_vi("x", [1, 5, 8, 8])], [_vi("y", None)])
    with pytest.raises(ConfigError, match="layout"):
        OnnxModel(_save(five, tmp_path, "five.onnx"))
    with pytest.raises(ConfigError, match="5 channels"):
        OnnxModel(_save(five, tmp_path, "five.onnx"), layout="NCHW")
    with pytest.raises(ConfigError, match="input_size"):
        OnnxModel(_grey_mean_model(tmp_path), input_size=(32, 32))


def test_python_and_opencv_models():
    import cv2

    def blobs(frame):
        g = cv2.cvtColor(frame, cv2.COLOR_RGB2GRAY)
        _, th = cv2.threshold(g, 127, 255, cv2.THRESH_BINARY)
        n, _ = cv2.connectedComponents(th)
        return n - 1

    frame = np.zeros((40, 40, 3), np.uint8)
    frame[5:10, 5:10] = 255
    frame[20:30, 20:25] = 255
    m = OpenCVModel(blobs, macs=30 * 40 * 40)
    assert m(frame) == 2 and m.macs == 48000 and m.name == "blobs"
    with pytest.raises(ConfigError, match="macs"):
        OpenCVModel(blobs, macs=None)
    with pytest.raises(ConfigError, match="callable"):
        PythonModel(42)
    assert PythonModel(len).macs is None


# -- templates ----------------------------------------------------------------------------
def test_counter_template_subclass_is_a_model(tmp_path):
    class CrowdCounter(Counter):
        def inference(self, data):
            return float(self.model(data).sum()) * self.params_.get("gain", 1.0)

    c = CrowdCounter().load_model(_grey_mean_model(tmp_path), gain=2.0)
    assert c.macs == 768 and c.params == 3 and c.params_ == {"gain": 2.0}
    frame = np.full((16, 16, 3), 255, np.uint8)
    assert c(frame) == pytest.approx(2 * 256)
    plain = Counter().load_model(_grey_mean_model(tmp_path))
    assert plain(frame) == pytest.approx(256)
    t = Task(c, period_s=1.0)
    r = TaskRunner(t).bind(np.random.default_rng(0))
    r.on_frame(0.0, frame, truth=[0] * 3)
    ev = r.advance(10.0)
    assert len(ev) == 1 and ev[0].ok and ev[0].count == pytest.approx(512)
    assert not c.learns_in_flight


def test_template_without_inference_fails_in_flight_not_the_flight():
    class Boxes(Detector):
        macs = 1000

    t = Task(Boxes(macs=1000), period_s=1.0, name="boxes")
    r = TaskRunner(t).bind(np.random.default_rng(0))
    for i in range(3):
        r.on_frame(float(i), np.zeros((8, 8, 3), np.uint8))
        r.advance(float(i) + 0.5)
    k = r.kpis()
    assert k["inference_failures"] == 3 and k["inference_count"] == 0
    assert "not implemented" in r.events[0].error


# -- Task validation ---------------------------------------------------------------------
def test_task_validation_errors():
    m = PythonModel(len, macs=10)
    with pytest.raises(ConfigError, match="period_s"):
        Task(m, period_s=0)
    with pytest.raises(ConfigError, match="raspberry-pi-4"):
        Task(m, device="raspberry-pi4")
    with pytest.raises(ConfigError, match="wifi-80211n"):
        Task(m, execution="remote", link="wifi-80211")
    with pytest.raises(ConfigError, match="execution.*'onboard', 'remote'"):
        Task(m, execution="cloud")
    with pytest.raises(ConfigError, match="on_busy"):
        Task(m, on_busy="skip")
    with pytest.raises(ConfigError, match="macs = None"):
        Task(PythonModel(len))
    Task(PythonModel(len), latency="measured")        # fine: measured needs no MACs
    with pytest.raises(ConfigError, match="jpeg_quality"):
        Task(m, jpeg_quality=101)
    assert Task(m, name="count").to_dict()["device"] is None     # the drone's own computer


# -- the runner on a fake clock ------------------------------------------------------------
def _fly(task, *, seconds=20.0, dt=0.05, frame=None, truth=None, pos=(0.0, 0.0, 30.0), seed=0):
    """Drive a runner like the mission loop: on_frame when due, advance, take_usage."""
    r = TaskRunner(task).bind(np.random.default_rng(seed))
    frame = np.zeros((48, 64, 3), np.uint8) if frame is None else frame
    usage = np.zeros(6)
    events = []
    n = int(round(seconds / dt))
    for i in range(n + 1):
        t = i * dt
        if r.due(t):
            f = frame(r.frames) if callable(frame) else frame
            tr = truth(r.frames) if callable(truth) else truth
            r.on_frame(t, f, tr, pos)
        events += r.advance(t)
        u = r.take_usage()
        assert u[0] <= dt + 1e-9
        usage += u
    return r, events, usage


BIG = PythonModel(lambda f: 0.0, macs=3_000_000_000, name="big")   # 2.0 s on a Pi 4


def test_big_model_drops_frames_on_a_pi_but_not_on_an_orin():
    r_pi, _, use_pi = _fly(Task(BIG, period_s=0.5, device="raspberry-pi-4"))
    r_orin, _, use_orin = _fly(Task(BIG, period_s=0.5, device="jetson-orin-nano"))
    k_pi, k_orin = r_pi.kpis(), r_orin.kpis()
    assert k_pi["frames_dropped"] > 0
    assert k_orin["frames_dropped"] == 0 and k_orin["inference_count"] == 40
    rpi = device("raspberry-pi-4")
    assert k_pi["inference_latency_p50_s"] == pytest.approx(rpi.overhead_s + 3e9 / rpi.macs_per_s)
    # busy time handed to the energy model adds up to the KPI, and fits in the flight
    assert use_pi[0] == pytest.approx(k_pi["cpu_time_s"]) and k_pi["cpu_time_s"] <= 20.0
    assert k_orin["cpu_time_s"] == pytest.approx(40 * (0.002 + 3e9 / 4e11), rel=1e-6)
    # queueing instead of dropping: nothing dropped (within max_queue), latency grows
    r_q, ev_q, _ = _fly(Task(BIG, period_s=1.5, device="raspberry-pi-4", on_busy="queue"))
    kq = r_q.kpis()
    assert kq["frames_dropped"] == 0
    lat = [e.latency_s for e in ev_q]
    assert lat[0] == pytest.approx(2.01) and all(b > a for a, b in zip(lat, lat[1:]))


def _scene(i):
    """A smooth synthetic 240x320 frame, different per frame index."""
    y, x = np.mgrid[0:240, 0:320]
    img = np.stack([(x + 3 * i) % 256, (y * 2) % 256, ((x + y) // 2 + i) % 256], axis=2)
    return img.astype(np.uint8)


MID = PythonModel(lambda f: float(f.mean() > 0), macs=30_000_000, name="mid")  # 0.03 s on a Pi


def _textured(i):
    """A 480x640 frame with texture, like an aerial photo: ~140 kB as JPEG q90."""
    import cv2
    small = np.random.default_rng(i).integers(0, 256, (120, 160, 3), dtype=np.uint8)
    return cv2.resize(small, (640, 480), interpolation=cv2.INTER_LINEAR)


def test_remote_is_slower_than_onboard_over_a_distant_link():
    pos = (550.0, 0.0, 30.0)     # ~550 m from the ground station: 6.5 Mbit/s, lossy
    on, _, use_on = _fly(Task(MID, period_s=2.0), frame=_textured, pos=pos)
    rem, ev, use_rem = _fly(Task(MID, period_s=2.0, execution="remote"), frame=_textured, pos=pos)
    k_on, k_rem = on.kpis(), rem.kpis()
    assert k_rem["inference_latency_p50_s"] > 3 * k_on["inference_latency_p50_s"]
    assert k_rem["inference_count"] > 0 and all(e.ok for e in ev)
    # close to the ground station remote wins: the ground GPU is 3000x faster
    near, _, _ = _fly(Task(MID, period_s=2.0, execution="remote"), frame=_textured,
                      pos=(20.0, 0.0, 30.0))
    assert near.kpis()["inference_latency_p50_s"] < k_rem["inference_latency_p50_s"]
    # the drone still works for remote inference (JPEG encoding) but much less
    enc = 480 * 640 * JPEG_MACS_PER_PIXEL / device("raspberry-pi-4").macs_per_s
    assert k_rem["cpu_time_s"] == pytest.approx(len(ev) * enc, rel=1e-6)
    assert k_rem["cpu_time_s"] < k_on["cpu_time_s"]
    # onboard sends only small results (no crowd), remote sends frames up and results down
    assert use_on[1] < use_rem[1] and use_rem[3] > 0


def test_remote_tx_bytes_are_the_real_jpeg_sizes():
    slow = Link("slow-lossless", rates=((-90.0, 2e6),), fixed_rate=True, loss_floor=0.0,
                jitter_s=0.0, per_packet_s=0.0)
    t = Task(MID, period_s=2.0, execution="remote", link=slow, jpeg_quality=80)
    r, ev, use = _fly(t, frame=_scene, seconds=10.0)
    sizes = [len(encode_jpeg(_scene(e.frame_index), 80)) for e in ev]
    assert [e.tx_bytes for e in ev] == sizes
    r.advance(100.0)                          # let the last request finish
    tail = r.take_usage()
    ev += r.events[len(ev):]
    sizes = [len(encode_jpeg(_scene(e.frame_index), 80)) for e in ev]
    assert use[1] + tail[1] == sum(sizes) == r.summary()["tx_bytes"]
    assert use[3] + tail[3] == 256 * len(ev)  # result messages down
    # and the latency is the transfer time of those bytes at 2 Mbit/s plus compute
    e = ev[0]
    up = (sizes[0] + math.ceil(sizes[0] / 1460) * slow.header_bytes) * 8 / 2e6
    assert e.latency_s > up


def test_lossy_remote_runs_reproduce_from_the_seed():
    t = Task(MID, period_s=1.0, execution="remote")
    runs = [_fly(t, frame=_scene, pos=(560.0, 0.0, 30.0), seed=s, seconds=8.0) for s in (3, 3, 4)]
    lat = [[e.latency_s for e in ev] for _, ev, _ in runs]
    assert lat[0] == lat[1]
    assert runs[0][0].kpis() == runs[1][0].kpis()
    assert np.array_equal(runs[0][2], runs[1][2])
    assert lat[0] != lat[2]
    assert runs[0][0].summary()["retransmissions"] > 0


def test_out_of_range_remote_inference_fails_and_flight_goes_on():
    t = Task(MID, period_s=1.0, execution="remote")
    r, ev, _ = _fly(t, frame=_scene, pos=(2000.0, 0.0, 30.0), seconds=5.0)
    k = r.kpis()
    assert k["inference_failures"] == len(ev) > 0 and k["inference_count"] == 0
    assert "down" in ev[0].error


def test_failing_model_is_counted_and_the_flight_goes_on():
    calls = {"n": 0}

    def flaky(frame):
        calls["n"] += 1
        if calls["n"] % 2 == 0:
            raise RuntimeError("boom")
        return 3.0

    r, ev, _ = _fly(Task(PythonModel(flaky, macs=1000), period_s=1.0), seconds=9.5)
    k = r.kpis()
    assert k["inference_failures"] == 5 and k["inference_count"] == 5
    assert [e.ok for e in ev][:2] == [True, False] and ev[1].error == "RuntimeError: boom"


def test_onboard_alert_sends_the_annotated_frame_when_a_crowd_is_detected():
    counter = PythonModel(lambda f: 12.0, macs=1000)
    quiet = PythonModel(lambda f: 2.0, macs=1000)
    slow = Link("lossless", rates=((-90.0, 50e6),), fixed_rate=True, loss_floor=0.0)
    r, ev, use = _fly(Task(counter, period_s=1.0, link=slow), frame=_scene, seconds=4.5)
    assert all(e.alert_sent for e in ev) and all(e.tx_bytes > 10_000 for e in ev)
    r2, ev2, use2 = _fly(Task(quiet, period_s=1.0, link=slow), frame=_scene, seconds=4.5)
    assert [e.tx_bytes for e in ev2] == [256] * len(ev2) and not any(e.alert_sent for e in ev2)
    # encoding the alert costs SoC time
    assert r.kpis()["cpu_time_s"] > r2.kpis()["cpu_time_s"]


def test_detection_kpis_from_truth():
    # truth counts per frame: a crowd (>= 10) in frames 2-5 and 9-10; the model sees the
    # count written in the frame's first pixel, but misses the first two crowd frames
    truth = [0, 3, 12, 15, 14, 11, 2, 0, 0, 20, 20, 1]
    pred = [0, 3, 5, 6, 14, 11, 2, 12, 0, 20, 20, 1]

    def frame(i):
        f = np.zeros((4, 4, 3), np.uint8)
        f[0, 0, 0] = pred[i] if i < len(pred) else 0
        return f

    m = PythonModel(lambda f: float(f[0, 0, 0]), macs=1000)
    r, ev, _ = _fly(Task(m, period_s=1.0, crowd_threshold=10), frame=frame,
                    truth=lambda i: [None] * truth[i] if i < len(truth) else [], seconds=11.5)
    k = r.kpis()
    t, p = np.array(truth, float), np.array(pred, float)
    assert k["count_mae"] == pytest.approx(np.mean(np.abs(t - p)))
    assert k["detection_precision"] == pytest.approx(4 / 5)      # TP 4 (4, 5, 9, 10), FP 1 (7)
    assert k["detection_recall"] == pytest.approx(4 / 6)         # FN 2 (2, 3)
    assert k["detection_delay_frames"] == pytest.approx((2 + 0) / 2)
    s = r.summary()
    assert s["crowd_encounters"] == 2 and s["crowds_missed"] == 0


def test_crowd_metrics_edge_cases():
    m = crowd_metrics([np.nan, 1.0], [np.nan, np.nan], 10)
    assert math.isnan(m["count_mae"]) and math.isnan(m["detection_delay_frames"])
    m = crowd_metrics([20, 20, 0, 20], [np.nan, 1, 0, 1], 10)      # crowds never detected
    assert m["crowd_encounters"] == 2 and m["crowds_missed"] == 2
    assert math.isnan(m["detection_delay_frames"]) and m["detection_recall"] == 0.0
    assert count_of(np.ones((4, 4))) == 16.0 and count_of([1, 2]) == 2.0
    assert count_of({"count": 3}) == 3.0 and count_of(np.array([[7.0]])) == 7.0


def test_measured_latency_mode_runs_and_reports_spread(tmp_path):
    model = OnnxModel(_grey_mean_model(tmp_path))
    r, ev, _ = _fly(Task(model, period_s=1.0, latency="measured"), seconds=5.0)
    k = r.kpis()
    s = r.summary()
    scale = s["calibration"]["scale"]     # host seconds to the Pi 4's core (layer model)
    assert scale["rule"] == "layer model: onnxruntime/cpu/fp32, 1 thread"
    assert k["inference_count"] == 5 and k["inference_latency_p50_s"] >= scale["overhead_s"] > 0
    assert s["measured_wall_s"]["n"] == 6 and s["calibration"]["spread"] >= 0


def test_frames_before_the_period_are_ignored_and_the_grid_does_not_drift():
    r = TaskRunner(Task(PythonModel(len, macs=1), period_s=0.5)).bind(0)
    for i in range(101):                # every 0.03 s: a 33 Hz camera
        r.on_frame(i * 0.03, np.zeros((2, 2, 3), np.uint8))
    assert r.frames == 7               # t = 0, 0.51, 1.02, 1.5, 2.01, 2.52, 3.0
    assert r.next_frame_t == pytest.approx(3.5)


def test_measured_latency_of_an_onnx_model_on_a_gpu_deployment_says_what_it_measures(tmp_path):
    """The host's CPU time scaled to the computer's CPU is not the time on its GPU: say so."""
    model = OnnxModel(_grey_mean_model(tmp_path))
    with pytest.warns(UserWarning, match=r"latency='measured' times the model on this host's "
                                         r"CPU.*tensorrt on its gpu"):
        _fly(Task(model, period_s=1.0, latency="measured", device="jetson-orin-nano"),
             seconds=2.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")              # the Pi 4's CPU deployment: nothing to say
        _fly(Task(model, period_s=1.0, latency="measured", device="raspberry-pi-4"), seconds=2.0)
        _fly(Task(model, period_s=1.0, latency="measured", device="jetson-orin-nano",
                  runtime="onnxruntime", target="cpu"), seconds=2.0)
