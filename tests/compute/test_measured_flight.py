"""A profile written by ``flockai profile-device`` on this machine (ONNX Runtime
standing in for the drone's computer), used as a task's computer in flight, reproduces its
measured p50 and p95 within 5 %; the draws are seeded (same seed, same flight)."""

import numpy as np
import pytest
from onnx_nets import conv_net

import pytest_flockai as fa
from pytest_flockai.cli import main
from pytest_flockai.errors import ConfigError


def _net(path, width):
    return conv_net(path, width, side=48, batch=1, seed=1)


@pytest.fixture(scope="module")
def profiled(tmp_path_factory):
    d = tmp_path_factory.mktemp("measured")
    net, other = _net(d / "net.onnx", 16), _net(d / "other.onnx", 4)
    out = d / "host.json"
    assert main(["profile-device", str(net), "--runtime", "onnxruntime", "--threads", "1",
                 "--runs", "1000", "--warmup", "5", "--out", str(out)]) == 0
    return out, net, other


def _fly(profile_path, net, seed=0, duration=30.0):
    task = fa.Task(fa.ml.OnnxModel(net), period_s=0.01, alert="result",
                   device=fa.compute.profile(profile_path))
    return fa.Mission(fa.drone("dji-mavic-2-pro"), fa.pilots.Hover(altitude=3.0,
                                                                    duration=duration),
                      tasks=[task], seed=seed).run()


N_DRAWS = 20_000


@pytest.mark.slow
def test_a_measured_profile_in_flight_reproduces_its_p50_and_p95(profiled):
    out, net, _ = profiled
    dev = fa.compute.profile(out)
    samples = dev.latency_samples(net)
    p50, p95 = np.percentile(samples, 50), np.percentile(samples, 95)
    # in flight: every inference's latency is one of the measured samples, seeded
    k = _fly(out, net, duration=3.0).kpis
    assert k["inference_count"] >= 100 and k["frames_dropped"] == 0
    assert k["inference_latency_max_s"] in set(samples.tolist())
    assert _fly(out, net, duration=3.0).kpis == k
    # the flight's runner over many frames (a long flight, without rendering each frame)
    # frames no faster than the slowest measured inference, so that none is dropped even when
    # the profile was measured on a loaded machine
    dt = max(0.01, 1.5 * float(samples.max()))
    task = fa.Task(fa.ml.OnnxModel(net), period_s=dt, alert="result", device=dev)
    r = fa.ml.TaskRunner(task).bind(np.random.default_rng(0))
    frame = np.zeros((48, 48, 3), np.uint8)
    # 20,000 draws: the p95 of 4,000 uniform draws from 1,000 timings missed the timings' own
    # p95 by just over 5 % once in CI (the draws' p95 has a standard error of about 0.35
    # percentile points at 4,000, 0.15 at 20,000)
    for i in range(N_DRAWS):
        r.on_frame(dt * i, frame)
        r.advance(dt * i)
    r.advance(1e9)
    got = r.kpis()
    assert got["inference_count"] == N_DRAWS and got["frames_dropped"] == 0
    assert got["inference_latency_p50_s"] == pytest.approx(p50, rel=0.05)
    # within 5 % of the timings' own p95, or, where a loaded machine left the timings' tail
    # so sparse that neighbouring samples lie more than 5 % apart, within the draws' own
    # sampling error of it (3 standard errors: 0.45 percentile points at 20,000 draws)
    lo, hi = np.percentile(samples, (95 - 0.45, 95 + 0.45))
    p95_got = got["inference_latency_p95_s"]
    assert (p95_got == pytest.approx(p95, rel=0.05) or lo <= p95_got <= hi), (
        p95_got, p95, lo, hi)
    assert got["inference_latency_p95_s"] > got["inference_latency_p50_s"]
    # predict_latency answers from the samples too
    pred = fa.compute.predict_latency(net, dev)
    assert pred.method == "measured" and pred.seconds == pytest.approx(p50)


def test_a_model_the_profile_does_not_have_is_refused(profiled):
    out, _, other = profiled
    with pytest.raises(ConfigError, match="was not profiled"):
        _fly(out, other, duration=1.0)
