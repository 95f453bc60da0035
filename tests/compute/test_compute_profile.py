"""flockai profile-device on this computer (ONNX Runtime standing in for the drone's) and
compute.profile(): the measured samples, seeded draws, power, and bad profile files."""

import ctypes
import hashlib
import importlib.metadata
import json
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import onnx
import onnxruntime as ort
import pytest
from onnx_nets import conv_net

import pytest_flockai as fa
from pytest_flockai.cli import main
from pytest_flockai.compute.profile import from_dict, model_sha256
from pytest_flockai.compute.profiler import measure, write
from pytest_flockai.errors import ConfigError


def _net(tmp_path, name="net.onnx", width=16):
    return conv_net(tmp_path / name, width)


@pytest.fixture(scope="module")
def measured(tmp_path_factory):
    d = tmp_path_factory.mktemp("prof")
    a, b = _net(d, "small.onnx", 8), _net(d, "wide.onnx", 32)
    power = d / "meter.csv"
    power.write_text("power_w\n6.0\n6.5\n7.0\n")
    out = d / "profile.json"
    rc = main(["profile-device", str(a), str(b), "--runtime", "onnxruntime", "--threads", "1",
               "--runs", "200", "--warmup", "3", "--power-csv", str(power), "--idle-w", "2.5",
               "--name", "this-host", "--out", str(out)])
    assert rc == 0
    return out, a, b


def test_profile_device_writes_a_profile_that_loads(measured, tmp_path):
    out, a, b = measured
    dev = fa.compute.profile(out)
    assert dev.name == "this-host" and dev.runtime == "onnxruntime"
    assert dev.runtime_version == ort.__version__ and dev.threads == 1
    assert dev.target == "cpu" and dev.precision == "fp32"
    assert dev.host["cpu_count"] >= 1 and dev.host["machine"]
    assert json.loads(out.read_text())["runtime"]["libraries"]["onnx"] == onnx.__version__
    assert model_sha256(a) == hashlib.sha256(a.read_bytes()).hexdigest()
    assert set(dev.models) == {model_sha256(a), model_sha256(b)}
    small, wide = dev.latency_samples(a), dev.latency_samples(str(b))
    assert small.shape == wide.shape == (200,) and np.all(small > 0)
    assert np.median(wide) > np.median(small)          # 16x the MACs of the second conv
    assert dev.model("small").macs == 64 * 64 * 8 * 27 + 64 * 64 * 8 * 72 + 64 * 64 * 8 + 8 * 4096
    # the same model under another name: the same SHA-256, the same samples
    copy = tmp_path / "renamed.onnx"
    copy.write_bytes(a.read_bytes())
    np.testing.assert_array_equal(dev.latency_samples(copy), small)
    assert dev.busy_w == pytest.approx(6.5) and dev.idle_w == 2.5
    assert dev.energy_j(a) == pytest.approx(np.median(small) * 4.0)
    with pytest.raises(ConfigError, match="was not profiled on 'this-host'.*small"):
        dev.latency_samples(_net(tmp_path, "other.onnx", 4))
    # the file's bytes match by their SHA-256; others are named by size and hash, not dumped
    np.testing.assert_array_equal(dev.latency_samples(a.read_bytes()), small)
    other = (tmp_path / "other.onnx").read_bytes()
    with pytest.raises(ConfigError) as e:
        dev.latency_samples(other)
    digest = hashlib.sha256(other).hexdigest()[:12]
    assert f"model = <{len(other)} bytes of ONNX, SHA-256 {digest}>" in str(e.value)
    assert len(str(e.value)) < 300


def test_seeded_draws_repeat_and_reproduce_p50_p95(measured):
    out, a, _ = measured
    dev = fa.compute.profile(out)
    draws = [dev.sample_latency(a, np.random.default_rng(7)) for _ in range(3)]
    assert draws[0] == draws[1] == draws[2]
    rng1, rng2 = np.random.default_rng(11), np.random.default_rng(11)
    s1 = np.array([dev.sample_latency(a, rng1) for _ in range(2000)])
    s2 = dev.sample_latency(a, rng2, size=2000)            # the same stream, vectorised
    np.testing.assert_allclose(s1, s2, rtol=1e-12)
    measured_s = dev.latency_samples(a)
    assert set(s1.tolist()) <= set(measured_s.tolist())       # each draw one of the samples
    # the draws' quantiles sit within one percentile point of the measured ones (on this
    # shared machine the samples can have gaps, so not always within 5 % of the value)
    many = dev.sample_latency(a, 12, size=200_000)
    for q in (50, 95):
        lo, hi = np.percentile(measured_s, [q - 1, q + 1])
        assert lo <= np.percentile(many, q) <= hi
    # on a profile of 1,000 known samples, the draws' p50 and p95 are within 5 %
    doc = json.loads(out.read_text())
    known = np.random.default_rng(5).lognormal(np.log(0.05), 0.3, 1000)
    doc["models"][0]["latency_s"] = known.tolist()
    dev2 = from_dict(doc)
    d = dev2.sample_latency(doc["models"][0]["sha256"], np.random.default_rng(1), size=20_000)
    for q in (50, 95):
        assert np.percentile(d, q) == pytest.approx(np.percentile(known, q), rel=0.05)
    assert np.percentile(d, 95) > 1.4 * np.percentile(d, 50)


def _doc(out):
    return json.loads(out.read_text())


@pytest.mark.parametrize("edit, field", [
    (lambda d: d.update(schema="other/1"), "'schema'"),
    (lambda d: d.pop("name"), "'name'"),
    (lambda d: d["runtime"].update(name="coreml"), "'name' = 'coreml'"),
    (lambda d: d["runtime"].update(precision="fp64"), "'precision' = 'fp64'"),
    (lambda d: d["runtime"].update(threads=-1), "'threads' = -1"),
    (lambda d: d.update(models=[]), "'models' = \\[\\]"),
    (lambda d: d["models"][1].update(latency_s=[0.01, -1.0]), "models\\[1\\]: field 'latency_s'"),
    (lambda d: d["models"][0].update(sha256="abc"), "models\\[0\\]: field 'sha256' = 'abc'"),
    (lambda d: d["power"].update(busy_w="hot"), "power: field 'busy_w' = 'hot'"),
])
def test_bad_profile_files_name_the_field(measured, tmp_path, edit, field):
    doc = _doc(measured[0])
    edit(doc)
    p = tmp_path / "bad.json"
    p.write_text(json.dumps(doc))
    with pytest.raises(ConfigError, match=field):
        fa.compute.profile(p)


def test_not_a_profile_and_bad_cli_input(tmp_path, capsys, measured):
    (tmp_path / "x.json").write_text("{not json")
    with pytest.raises(ConfigError, match="is not a profile"):
        fa.compute.profile(tmp_path / "x.json")
    with pytest.raises(ConfigError, match="does not exist"):
        fa.compute.profile(tmp_path / "none.json")
    with pytest.raises(ConfigError, match="expected a JSON object"):
        from_dict([1, 2])
    net, out = measured[1], tmp_path / "p.json"
    for args, text in ((["--runtime", "tensorrt"], "--runtime = 'tensorrt' is not allowed"),
                       (["--runs", "0"], "--runs = 0"),
                       (["--input-shape", "1x3xA"], "--input-shape = '1x3xA'"),
                       (["--jetson-rails"], "no INA3221 input rail"),
                       (["--power-csv", str(net)], "--power-csv")):
        assert main(["profile-device", str(net), "--out", str(out), *args]) == 2
        assert text in capsys.readouterr().err
    assert not out.exists()


def test_power_from_a_timed_meter_log_and_opencv_dnn(tmp_path):
    net = _net(tmp_path, "m.onnx", 8)
    now = time.time()
    times = np.arange(now - 30.0, now + 120.0, 0.01)
    meter = tmp_path / "meter.csv"
    meter.write_text("time_s,power_w\n" + "".join(
        f"{t:.3f},{2.0 if t < now else 7.0}\n" for t in times))
    doc = measure([net], runtime="opencv-dnn", runs=5, warmup=1, input_shape="1x3x64x64",
                  power_csv=meter, name="meter-test")
    write(doc, tmp_path / "p.json")
    dev = fa.compute.profile(tmp_path / "p.json")
    assert dev.runtime == "opencv-dnn" and dev.runtime_version == cv2.__version__
    assert dev.idle_w == pytest.approx(2.0, abs=0.1)           # samples before the start
    assert dev.busy_w == 7.0 and "meter.csv" in dev.power_source   # samples in the runs
    assert dev.latency_samples(net).shape == (5,)
    assert dev.model(net).input_shape == (1, 3, 64, 64)
    late = tmp_path / "late.csv"
    late.write_text("time_s,power_w\n1.0,3.0\n")
    with pytest.raises(ConfigError, match="no sample falls in the timed runs"):
        measure([net], runs=2, warmup=0, power_csv=late)
    bad = tmp_path / "bad.onnx"
    bad.write_bytes(net.read_bytes()[:-40])                # a truncated model file
    with pytest.raises(ConfigError, match="bad.onnx"):
        measure([bad], runs=1, warmup=0)


def test_input_shape_fills_the_open_dims_and_keeps_the_fixed_ones(tmp_path):
    """One --input-shape for a dynamic model and a fixed one: the dynamic model runs at it,
    the fixed one at its own size (ONNX Runtime would refuse any other)."""
    open_net = conv_net(tmp_path / "open.onnx", 8, side="s")          # [n, 3, s, s]
    fixed = conv_net(tmp_path / "fixed.onnx", 8, side=32, batch=1)    # [1, 3, 32, 32]
    doc = measure([open_net, fixed], runs=3, warmup=1, input_shape="1x3x48x48")
    write(doc, tmp_path / "p.json")
    dev = fa.compute.profile(tmp_path / "p.json")
    assert dev.model(open_net).input_shape == (1, 3, 48, 48)
    assert dev.model(fixed).input_shape == (1, 3, 32, 32)


def test_openvino_times_the_onnx_file_itself_and_records_what_it_computed_with(tmp_path):
    """--runtime openvino reads the ONNX file a task flies (its SHA-256 matches), runs it at
    the threads asked, records the precision OpenVINO chose, and the measured samples are
    what predict_latency and a flight's draws answer with."""
    ov = pytest.importorskip("openvino")
    small, wide = _net(tmp_path, "s.onnx", 8), _net(tmp_path, "w.onnx", 32)
    doc = measure([small, wide], runtime="openvino", threads=1, runs=40, warmup=3,
                  input_shape="1x3x64x64", name="ov-host")
    write(doc, tmp_path / "ov.json")
    dev = fa.compute.profile(tmp_path / "ov.json")
    rt = doc["runtime"]
    assert dev.runtime == "openvino" and dev.runtime_version == ov.__version__
    assert rt["libraries"]["openvino"] == ov.__version__
    assert rt["execution"]["device"] == "CPU" and rt["execution"]["threads"] == 1
    # the precision OpenVINO computed in, as the profile's precision class
    chosen = rt["execution"]["precision"]
    assert chosen in ("f32", "bf16", "f16")
    assert dev.precision == ("fp32" if chosen == "f32" else "fp16")
    assert set(dev.models) == {model_sha256(small), model_sha256(wide)}
    assert np.median(dev.latency_samples(wide)) > np.median(dev.latency_samples(small))
    p = fa.compute.predict_latency(small, dev)
    assert p.method == "measured" and p.seconds == pytest.approx(
        np.percentile(dev.latency_samples(small), 50))
    assert (p.runtime, p.target, p.precision, p.threads) == ("openvino", "cpu",
                                                            dev.precision, 1)


def test_openvino_refusals_say_why(tmp_path, monkeypatch, capsys):
    """Not installed, a device it does not have, a file it cannot read: one-line errors."""
    pytest.importorskip("openvino")
    net, out = _net(tmp_path, "n.onnx", 8), tmp_path / "p.json"
    bad = tmp_path / "bad.onnx"
    bad.write_bytes(net.read_bytes()[:-40])
    with pytest.raises(ConfigError, match="bad.onnx"):
        measure([bad], runtime="openvino", runs=1, warmup=0)
    import openvino
    if "GPU" not in openvino.Core().available_devices:
        assert main(["profile-device", str(net), "--runtime", "openvino", "--target", "gpu",
                     "--out", str(out)]) == 2
        assert "--target = 'gpu' is not allowed here: OpenVINO" in capsys.readouterr().err
    assert main(["profile-device", str(net), "--runtime", "opencv-dnn", "--target", "gpu",
                 "--out", str(out)]) == 2
    assert "allowed: ['cpu']" in capsys.readouterr().err
    monkeypatch.setitem(sys.modules, "openvino", None)      # as if it were not installed
    with pytest.raises(ConfigError, match=r"OpenVINO is not installed.*pip install openvino"):
        measure([net], runtime="openvino", runs=1, warmup=0)
    assert not out.exists()


DATA = Path(__file__).resolve().parent / "data"       # written by data/make_tflite.py


def test_tflite_times_a_tflite_file_for_the_onnx_file_it_stands_for(tmp_path):
    """--runtime tflite times .tflite files with LiteRT; --onnx names the ONNX file each
    stands for, so the profile matches the model a task flies (and counts its MACs),
    while the timed file is kept beside it."""
    pytest.importorskip("ai_edge_litert")
    flt, q8 = DATA / "tiny_cnn.tflite", DATA / "tiny_cnn_int8.tflite"
    a = conv_net(tmp_path / "a.onnx", 8, side=64, batch=1)
    b = conv_net(tmp_path / "b.onnx", 16, side=64, batch=1)
    doc = measure([flt, q8], runtime="tflite", threads=1, runs=30, warmup=2,
                  stands_for=[a, b], name="pi")
    write(doc, tmp_path / "t.json")
    dev = fa.compute.profile(tmp_path / "t.json")
    assert dev.runtime == "tflite" and dev.target == "cpu" and dev.threads == 1
    assert dev.runtime_version == importlib.metadata.version("ai-edge-litert")
    assert dev.precision == "fp32"                      # the first model's: a float graph
    assert doc["runtime"]["execution"]["package"] == "ai-edge-litert"
    assert set(dev.models) == {model_sha256(a), model_sha256(b)}
    entry = doc["models"][1]
    assert entry["file"] == {"path": str(q8), "format": "tflite",
                             "sha256": hashlib.sha256(q8.read_bytes()).hexdigest()}
    assert entry["input_shape"] == [1, 64, 64, 3] and entry["macs"] == dev.model(b).macs > 0
    p = fa.compute.predict_latency(b, dev)
    assert p.method == "measured" and p.seconds == pytest.approx(
        np.percentile(dev.latency_samples(b), 50))
    # without --onnx the .tflite file is the model: matched by its own SHA-256 (and
    # without --runtime a .tflite file is timed with tflite)
    alone = fa.compute.profile(write_doc(measure([q8], runs=3, warmup=1), tmp_path / "q.json"))
    assert alone.runtime == "tflite"
    assert alone.precision == "int8" and alone.latency_samples(q8).shape == (3,)
    assert alone.model(q8).macs is None


def write_doc(doc, path):
    write(doc, path)
    return path


@pytest.mark.parametrize("models, kw, text", [
    (["a.onnx"], {"runtime": "tflite"}, "is an ONNX file; --runtime tflite runs .tflite"),
    ([DATA / "tiny_cnn.tflite"], {"runtime": "onnxruntime"},
     r"is a TF Lite \(.tflite\) file; --runtime onnxruntime"),
    ([DATA / "tiny_cnn.tflite"], {"runtime": "tflite", "stands_for": ["a.onnx", "a.onnx"]},
     "--onnx given 2 time"),
    (["a.onnx"], {"stands_for": ["a.onnx"]}, "an ONNX model itself"),
    ([DATA / "tiny_cnn.tflite"], {"runtime": "tflite", "stands_for": ["big.onnx"]},
     "differ in size"),
    ([DATA / "tiny_cnn.tflite"], {"runtime": "tflite", "stands_for": ["none.onnx"]},
     "expected an existing .onnx file"),
    ([DATA / "tiny_cnn_int8.tflite"], {"runtime": "edgetpu", "target": "cpu"},
     r"--target = 'cpu' is not allowed with --runtime edgetpu; allowed: \['npu'\]"),
])
def test_tflite_refusals_name_the_input(tmp_path, models, kw, text):
    pytest.importorskip("ai_edge_litert")
    conv_net(tmp_path / "a.onnx", 8, side=64, batch=1)
    conv_net(tmp_path / "big.onnx", 8, side=96, batch=1)
    where = {m: m if isinstance(m, Path) else tmp_path / m for m in models}
    kw = dict(kw, runs=1, warmup=0)
    if "stands_for" in kw:
        kw["stands_for"] = [tmp_path / o for o in kw["stands_for"]]
    with pytest.raises(ConfigError, match=text):
        measure([where[m] for m in models], **kw)


def test_ncnn_times_a_param_file_with_the_input_shape_of_its_onnx(tmp_path):
    """--runtime ncnn times MODEL.param (with its .bin) in ncnn's binding: the input shape
    from --onnx (ncnn's files do not hold it) or --input-shape; identified by the ONNX
    file it stands for, or else by the .param and .bin bytes."""
    ncnn = pytest.importorskip("ncnn")
    param = DATA / "tiny.ncnn.param"                  # conv_net(8, 64x64) by pnnx
    a = conv_net(tmp_path / "tiny.onnx", 8, side=64, batch=1)
    doc = measure([param], runtime="ncnn", threads=1, runs=30, warmup=2, stands_for=[a])
    write(doc, tmp_path / "n.json")
    dev = fa.compute.profile(tmp_path / "n.json")
    assert dev.runtime == "ncnn" and dev.runtime_version == str(ncnn.__version__)
    assert dev.precision == "fp32" and doc["runtime"]["execution"]["threads"] == 1
    assert doc["runtime"]["execution"]["vulkan"] is False
    assert dev.model(a).input_shape == (1, 3, 64, 64) and dev.model(a).macs > 0
    assert doc["models"][0]["file"]["format"] == "ncnn"
    assert fa.compute.predict_latency(a, dev).seconds == pytest.approx(
        np.percentile(dev.latency_samples(a), 50))
    # alone: --input-shape, and the model is the .param and .bin bytes
    alone = fa.compute.profile(write_doc(
        measure([param], runtime="ncnn", runs=3, warmup=1, input_shape="1x3x64x64"),
        tmp_path / "m.json"))
    want = hashlib.sha256(param.read_bytes() + (DATA / "tiny.ncnn.bin").read_bytes())
    assert set(alone.models) == {want.hexdigest()}
    assert alone.latency_samples(param).shape == (3,)


@pytest.mark.parametrize("kw, text", [
    ({}, "ncnn's files do not hold the input shape; give --input-shape"),
    ({"input_shape": "2x3x64x64"}, "expected 1xCxHxW"),
    ({"runtime": "onnxruntime"}, r"is an ncnn \(.param\) file; --runtime onnxruntime runs "
                                 r".onnx files \(an ncnn \(.param\) file: --runtime ncnn\)"),
])
def test_ncnn_refusals_name_the_input(kw, text):
    pytest.importorskip("ncnn")
    with pytest.raises(ConfigError, match=text):
        measure([DATA / "tiny.ncnn.param"], **{"runtime": "ncnn", "runs": 1, "warmup": 0, **kw})


def test_ncnn_without_its_weights_or_its_binding(tmp_path, monkeypatch):
    pytest.importorskip("ncnn")
    lone = tmp_path / "lone.param"
    lone.write_bytes((DATA / "tiny.ncnn.param").read_bytes())
    with pytest.raises(ConfigError, match=r"its weights .*lone.bin' do not exist"):
        measure([lone], runtime="ncnn", runs=1, warmup=0, input_shape="1x3x64x64")
    monkeypatch.setitem(sys.modules, "ncnn", None)          # as if it were not installed
    with pytest.raises(ConfigError, match=r"ncnn's Python binding is not installed.*pip install ncnn"):
        measure([DATA / "tiny.ncnn.param"], runtime="ncnn", runs=1, warmup=0,
                input_shape="1x3x64x64")


def test_edgetpu_without_its_delegate_and_no_litert(monkeypatch):
    """The Edge TPU's delegate library missing, and no LiteRT at all: one-line errors."""
    pytest.importorskip("ai_edge_litert")
    q8 = DATA / "tiny_cnn_int8.tflite"
    try:
        ctypes.CDLL("libedgetpu.so.1")
    except OSError:
        with pytest.raises(ConfigError, match="Edge TPU delegate libedgetpu.so.1 does not load"):
            measure([q8], runtime="edgetpu", runs=1, warmup=0)
    for mod in ("ai_edge_litert.interpreter", "tflite_runtime.interpreter", "tensorflow"):
        monkeypatch.setitem(sys.modules, mod, None)        # as if none were installed
    with pytest.raises(ConfigError, match="no LiteRT is installed.*pip install ai-edge-litert"):
        measure([q8], runtime="tflite", runs=1, warmup=0)


def test_openvino_then_a_flight_with_a_watchdog_in_one_process(tmp_path):
    """Two models profiled with OpenVINO, then a flight whose max_wall_s watchdog fires
    (SIGALRM), in one fresh process: it used to die in the signal handler (exit -11)
    once OpenVINO's Core was destroyed; the Core is now kept for the process."""
    pytest.importorskip("openvino")
    a, b = _net(tmp_path, "a.onnx", 8), _net(tmp_path, "b.onnx", 32)
    code = (
        "import pytest_flockai as fa\n"
        "from pytest_flockai.compute.profiler import measure\n"
        f"measure([{str(a)!r}, {str(b)!r}], runtime='openvino', threads=1, runs=3, warmup=1,\n"
        "        input_shape='1x3x64x64')\n"
        "try:\n"
        "    fa.Mission(fa.drone('crazyflie-2-1'), fa.pilots.Hover(1.0), until=600,\n"
        "               max_wall_s=0.2).run()\n"
        "except fa.SimulationError as e:\n"
        "    print(e.result.end_reason)\n")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0 and p.stdout.strip() == "wall_time", (p.returncode, p.stderr[-500:])
