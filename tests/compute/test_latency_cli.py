"""``flockai predict-latency``: the layer model from the shell, one row per computer and
runtime, the same seconds as ``predict_latency``, bad input refused in one line (exit 2)."""

import json

import pytest
from onnx_nets import conv_net

from pytest_flockai.cli import main
from pytest_flockai.compute import device, devices, predict_latency


@pytest.fixture(scope="module")
def net(tmp_path_factory):
    return conv_net(tmp_path_factory.mktemp("cli") / "net.onnx", side=64)


def test_every_computer_and_runtime_gets_the_predicted_latency(net, tmp_path, capsys):
    out = tmp_path / "rows.json"
    assert main(["predict-latency", str(net), "--json", str(out)]) == 0
    text = capsys.readouterr().out
    assert text.startswith("flockai predict-latency: net: ") and "input 1x3x64x64" in text
    doc = json.loads(out.read_text())
    got = {(r["computer"], r["runtime"]): r for r in doc["rows"]}
    for name in devices():
        dev = device(name)
        for rt in dev.runtimes:
            want = predict_latency(net, name, runtime=rt, input_shape=(1, 3, 64, 64))
            row = got[(name, rt)]
            assert row["seconds"] == pytest.approx(want.seconds)
            assert row["precision"] == want.precision and row["band"] == list(want.band)
            assert f"{1e3 * want.seconds:10.2f}" in text
    assert len(got) == sum(len(device(n).runtimes) for n in devices())


def test_a_named_deployment_and_what_a_computer_cannot_run(net, capsys):
    assert main(["predict-latency", str(net), "--computer", "raspberry-pi-5", "--runtime", "ncnn",
                 "--precision", "int8"]) == 0
    text = capsys.readouterr().out
    want = predict_latency(net, "raspberry-pi-5", runtime="ncnn", precision="int8")
    assert "ncnn/cpu/int8" in text and f"{want.milliseconds:10.2f}" in text
    # every computer but the runtime named: the ones without it are listed, not an error
    assert main(["predict-latency", str(net), "--runtime", "tensorrt"]) == 0
    text = capsys.readouterr().out
    assert "jetson-orin-nano " in text and "left out: raspberry-pi-4/tensorrt:" in text
    # both named: it is the error it is for predict_latency
    assert main(["predict-latency", str(net), "--computer", "raspberry-pi-4",
                 "--runtime", "tensorrt"]) == 2
    assert "'tensorrt' cannot run on computer 'raspberry-pi-4'" in capsys.readouterr().err


@pytest.mark.parametrize("args, says", [
    (["--runtime", "trt"], "runtime = 'trt' is not allowed"),
    (["--precision", "fp8"], "precision = 'fp8' is not allowed"),
    (["--computer", "pi4"], "unknown device 'pi4'"),
    (["--input-shape", "1x3xAx64"], "--input-shape = '1x3xAx64' is not allowed"),
])
def test_bad_input_is_one_line_naming_it(net, capsys, args, says):
    assert main(["predict-latency", str(net), *args]) == 2
    err = capsys.readouterr().err
    assert says in err and err.count("\n") == 1


def test_a_dynamic_input_asks_for_the_flag_not_the_python_argument(capsys):
    """crowd_cnn.onnx takes any image size ([1, 3, ?, ?]): the shell user is told which flag
    to give, and the run with it predicts."""
    from pathlib import Path
    model = Path(__file__).resolve().parents[2] / "fixtures" / "models" / "crowd_cnn.onnx"
    assert main(["predict-latency", str(model), "--computer", "raspberry-pi-4"]) == 2
    err = capsys.readouterr().err
    assert "input 'image'" in err and "e.g. --input-shape 1x3x480x640" in err
    assert "input_shape=" not in err and err.count("\n") == 1
    assert main(["predict-latency", str(model), "--computer", "jetson-orin-nano",
                 "--input-shape", "1x3x240x320"]) == 0
    rows = [ln.split() for ln in capsys.readouterr().out.splitlines()[2:] if ln.strip()]
    # threads mean something on a CPU only
    assert {r[2] for r in rows if "/gpu/" in r[1]} == {"-"}
    assert {r[2] for r in rows if r[1].startswith("tflite/cpu/")} == {"1"}
