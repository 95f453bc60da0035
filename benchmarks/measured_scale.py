"""How ``Task(latency="measured")`` scales this host's time to a computer, against the layer
model (``compute.predict_latency``) of the same network on that computer's CPU core.

Dense networks of several sizes (3x3 convolutions + ReLU, built in memory, none of them the
calibration network) are timed with ONNX Runtime on one host core, interleaved round by
round with a fresh calibration (``compute.latency.calibrate(force=True)``), and scaled to
each computer two ways:

- ``layer``: ``compute.latency.scale_to_device`` (the calibration network's layer-model time
  on one core of the computer / its host time);
- ``MAC rate``: the rule it replaced, ``overhead_s + wall * host_macs_per_s / macs_per_s``.

Printed per computer and network: each scaled time over the layer model's prediction of that
network (ONNX Runtime, cpu, fp32, 1 thread), the median over rounds. 1.00 means the host
measurement, scaled, says what the layer model says. The load average is printed before
and after: the figures are ratios within one run.

    PYTHONPATH=$PWD python benchmarks/measured_scale.py --rounds 5
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np
import onnxruntime as ort
from onnx import TensorProto, helper, numpy_helper

from pytest_flockai.compute.devices import device
from pytest_flockai.compute.latency import calibrate, host_scale, scale_to_device
from pytest_flockai.compute.predict import predict_latency

COMPUTERS = ("raspberry-pi-4", "raspberry-pi-5", "jetson-nano-10w", "jetson-orin-nano",
             "jetson-orin-nx-16gb")
NETS = {"dense-32x32x32": (32, 32, 3), "dense-48x48x48": (48, 48, 4),
        "dense-64x64x96": (64, 96, 4)}         # (side, channels, layers)


def dense(side: int, ch: int, layers: int) -> bytes:
    rng = np.random.default_rng(side * 1000 + ch)
    nodes, inits, name, c_in = [], [], "x", 8
    for i in range(layers):
        w = (rng.standard_normal((ch, c_in, 3, 3)) * 0.05).astype(np.float32)
        inits.append(numpy_helper.from_array(w, f"w{i}"))
        nodes += [helper.make_node("Conv", [name, f"w{i}"], [f"c{i}"], pads=[1, 1, 1, 1]),
                  helper.make_node("Relu", [f"c{i}"], [f"r{i}"])]
        name, c_in = f"r{i}", ch
    g = helper.make_graph(nodes, "dense", [helper.make_tensor_value_info(
        "x", TensorProto.FLOAT, [1, 8, side, side])], [helper.make_tensor_value_info(
            name, TensorProto.FLOAT, [1, ch, side, side])], inits)
    m = helper.make_model(g, opset_imports=[helper.make_opsetid("", 13)])
    m.ir_version = 8
    return m.SerializeToString()


def host_median(sess, x, runs: int) -> float:
    for _ in range(3):
        sess.run(None, {"x": x})
    t = []
    for _ in range(runs):
        t0 = time.perf_counter()
        sess.run(None, {"x": x})
        t.append(time.perf_counter() - t0)
    return float(np.median(t))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--runs", type=int, default=15)
    a = ap.parse_args()
    print(f"load average before: {os.getloadavg()[0]:.2f}")
    opts = ort.SessionOptions()
    opts.intra_op_num_threads = opts.inter_op_num_threads = 1
    nets = {k: dense(*v) for k, v in NETS.items()}
    sess = {k: ort.InferenceSession(b, opts, providers=["CPUExecutionProvider"])
            for k, b in nets.items()}
    xs = {k: np.zeros((1, 8, v[0], v[0]), np.float32) for k, v in NETS.items()}
    ratios: dict = {}
    for _ in range(a.rounds):
        cal = calibrate(force=True)
        for k in nets:
            wall = host_median(sess[k], xs[k], a.runs)
            for c in COMPUTERS:
                pred = predict_latency(nets[k], c, runtime="onnxruntime", target="cpu",
                                       precision="fp32", threads=1).seconds
                d = device(c)
                old = d.overhead_s + wall * cal.host_macs_per_s / d.macs_per_s
                ratios.setdefault((c, k), []).append(
                    (scale_to_device(wall, c, cal) / pred, old / pred))
    print(f"load average after: {os.getloadavg()[0]:.2f}")
    print("| computer | network | layer / layer model | MAC rate / layer model |")
    print("|---|---|---|---|")
    for (c, k), rs in ratios.items():
        new, old = np.median(np.asarray(rs), axis=0)
        print(f"| {c} | {k} | {new:.2f} | {old:.2f} |")
    print("scale per computer (factor: device seconds per host second):")
    cal = calibrate()
    for c in COMPUTERS:
        print(f"  {c}: {host_scale(c, cal).factor:.2f} "
              f"(MAC rate: {cal.host_macs_per_s / device(c).macs_per_s:.2f})")


if __name__ == "__main__":
    main()
