"""Latency on device profiles: modeled (deterministic) and measured (calibrated)."""

import time

import numpy as np
import onnxruntime as ort
import pytest
from onnx_nets import conv_net

from pytest_flockai.compute.devices import device
from pytest_flockai.compute.latency import (
    _calibration_model_bytes,
    calibrate,
    host_scale,
    measured_latency,
    modeled_latency,
    scale_to_device,
)
from pytest_flockai.compute.predict import predict_latency
from pytest_flockai.errors import ConfigError


def test_modeled_latency_is_the_formula_and_deterministic():
    rpi = device("raspberry-pi-4")
    want = rpi.overhead_s + 3e8 / rpi.macs_per_s
    runs = {modeled_latency(3e8, "raspberry-pi-4") for _ in range(5)}
    assert runs == {want}
    assert modeled_latency(3e8, rpi) == want
    assert modeled_latency(0, "jetson-orin-nano") == device("jetson-orin-nano").overhead_s
    # faster device, lower latency
    assert modeled_latency(3e8, "jetson-orin-nano") < modeled_latency(3e8, "jetson-nano-5w") < want


@pytest.mark.parametrize("bad", [None, -1, float("nan"), "many", True])
def test_modeled_latency_rejects_bad_macs(bad):
    with pytest.raises(ConfigError, match="macs"):
        modeled_latency(bad, "raspberry-pi-4")


def test_unknown_device_names_close_match():
    with pytest.raises(ConfigError, match="raspberry-pi-4"):
        modeled_latency(1, "raspberry-pi4")


def test_calibration_is_cached_and_scales_to_devices():
    cal = calibrate()
    assert calibrate() is cal
    assert cal.host_macs_per_s > 1e8 and cal.runs >= 3
    assert cal.p10_s <= cal.median_s <= cal.p90_s and cal.spread >= 0
    # the calibration net itself gets the layer model's time on one core of the computer
    rpi = device("raspberry-pi-4")
    want = predict_latency(_calibration_model_bytes(), rpi, runtime="onnxruntime",
                           target="cpu", precision="fp32", threads=1).seconds
    assert scale_to_device(cal.median_s, rpi, cal) == pytest.approx(want)
    out, secs, wall = measured_latency(np.add, 1, 2, device=rpi)
    assert out == 3 and secs >= host_scale(rpi, cal).overhead_s and wall >= 0


def test_host_scale_follows_the_computers_cpu_datasheets():
    cal = calibrate()
    f = {n: host_scale(n, cal) for n in ("raspberry-pi-4", "raspberry-pi-5", "jetson-nano-10w",
                                          "jetson-orin-nano", "coral-dev-board", "ground-gpu")}
    assert all("layer model: onnxruntime/cpu/fp32, 1 thread" == f[n].rule
               for n in ("raspberry-pi-4", "raspberry-pi-5", "jetson-nano-10w", "jetson-orin-nano"))
    # a Cortex-A76 core at 2.4 GHz outruns an A72 at 1.8 GHz; the Orin's A78AE the Nano's A57
    assert f["raspberry-pi-5"].factor < f["raspberry-pi-4"].factor
    assert f["jetson-orin-nano"].factor < f["jetson-nano-10w"].factor
    # no CPU runtime in the datasheet: the MAC-count rule, and the report says so
    for n in ("coral-dev-board", "ground-gpu"):
        assert f[n].rule.startswith("MAC-count rule") and n in f[n].rule
        assert f[n].factor == pytest.approx(cal.host_macs_per_s / device(n).macs_per_s)


def test_measured_latency_of_a_dense_network_agrees_with_the_layer_model(tmp_path):
    """Timed on the host and scaled, a dense network (two 3x3 convolutions of 48 channels
    on 48x48, unlike the calibration network in every shape) lands near the layer model's
    time on the computer's core (the MAC-count rule's guessed rate put it 4x too slow on a
    Pi 4)."""
    net = str(conv_net(tmp_path / "dense.onnx", width=48, side=48, batch=1))
    opts = ort.SessionOptions()
    opts.intra_op_num_threads = opts.inter_op_num_threads = 1
    sess = ort.InferenceSession(net, opts, providers=["CPUExecutionProvider"])
    x = np.random.default_rng(0).standard_normal((1, 3, 48, 48)).astype(np.float32)
    for _ in range(3):
        sess.run(None, {"x": x})
    cal = calibrate(force=True)             # host timings close together in time
    walls = []
    for _ in range(15):
        t0 = time.perf_counter()
        sess.run(None, {"x": x})
        walls.append(time.perf_counter() - t0)
    for name in ("raspberry-pi-4", "jetson-orin-nano"):
        measured = scale_to_device(float(np.median(walls)), name, cal)
        modeled = predict_latency(net, name, runtime="onnxruntime", target="cpu",
                                  precision="fp32", threads=1).seconds
        assert 0.4 < measured / modeled < 2.5, (name, measured, modeled)
