"""A team's own computer from its datasheet (``fa.compute.computer``): checked where it
enters, predicted through the same layer model as the package's profiles, banded by
leave-one-computer-out, and flown (the drone carries its power). Also: a drone whose
``device`` is changed after it is built carries that computer's power."""

import json
import tomllib

import pytest

import pytest_flockai as fa
from pytest_flockai.compute import DEVICES, own, predict, published, tuning
from pytest_flockai.compute.datasheets import COMPUTERS
from pytest_flockai.errors import ConfigError

CNN = fa.ml.shipped_path("crowd_cnn")
SHAPE = (1, 3, 240, 320)

ROCK = """
[computers.rock-5b]
name = "Radxa ROCK 5B (RK3588), big cores"
memory_mb = 8192
memory_bandwidth_gbs = 34.1
runtimes = ["onnxruntime", "tflite", "ncnn"]

[computers.rock-5b.cpu]
cores = 4
clock_ghz = 2.4
fp32_flop_per_cycle_per_core = 16
fp16_flop_per_cycle_per_core = 32

[computers.rock-5b.power]
idle_w = 1.5
busy_w = 8.0
"""


def builtin(name):
    with COMPUTERS.open("rb") as fh:
        return tomllib.load(fh)["computers"][name]


@pytest.fixture
def rock_file(tmp_path):
    p = tmp_path / "boards.toml"
    p.write_text(ROCK)
    return p


def test_a_copied_datasheet_predicts_what_the_profile_does_with_the_untuned_band():
    """The package's Pi 4 table under another name is the same computer to the layer model
    (nothing in the fit is per computer); only its band differs: a computer the fit never
    saw gets the leave-one-computer-out range."""
    mine = fa.compute.computer(builtin("raspberry-pi-4"), name="my-pi4")
    table = predict.efficiencies()
    for rt in ("onnxruntime", "ncnn", "tflite"):
        a = fa.compute.predict_latency(CNN, "raspberry-pi-4", runtime=rt, input_shape=SHAPE)
        b = fa.compute.predict_latency(CNN, mine, runtime=rt, input_shape=SHAPE)
        assert b.seconds == pytest.approx(a.seconds, rel=1e-12)
        assert b.energy_j == pytest.approx(a.energy_j, rel=1e-12)
        u = table["bands"]["untuned/*/cpu"]
        assert b.band == pytest.approx((b.seconds * u["lo"], b.seconds * u["hi"]))
    assert mine.deployments == DEVICES["raspberry-pi-4"].deployments
    assert "never tuned" in mine.source


def test_the_untuned_band_is_leave_one_computer_out_of_the_stored_fit():
    """A board predicted by a fit without it (the Coral board, the one NPU: one refit, the
    whole of loco is about 20 s): the stored figures are what the code gives, and the NPU's
    untuned band is the range of its held-out ratios; the profiles of tuned boards are
    listed, a power mode with its board."""
    rows, _ = published.load_rows()
    table = predict.efficiencies()
    cv = tuning.loco(rows, table["fallback"], boards=["coral-dev-board"])
    assert set(cv["per_board"]) == {"coral-dev-board"}
    for half, v in table["loco"]["per_board"]["coral-dev-board"].items():
        assert cv["per_board"]["coral-dev-board"][half] == pytest.approx(v), half
    assert tuning.loco_bands(cv)["untuned/*/npu"] == pytest.approx(table["bands"]["untuned/*/npu"])
    assert set(table["loco"]["per_board"]) == {published.board_of(r.computer)
                                               for r in rows}
    assert table["tuned_computers"] == tuning.tuned_computers(rows)
    assert "jetson-nano-5w" in table["tuned_computers"]       # the Nano's other power mode
    assert "ground-gpu" not in table["tuned_computers"]       # no published row


def test_a_file_of_computers_flies_and_predicts(rock_file):
    rock = fa.compute.computer(rock_file)               # one computer: no name needed
    assert rock.name == "rock-5b" and rock.runtimes == ("onnxruntime", "tflite", "ncnn")
    assert set(fa.compute.computers(rock_file)) == {"rock-5b"}
    p = fa.compute.predict_latency(CNN, rock, runtime="ncnn", input_shape=SHAPE)
    assert 0 < p.band[0] < p.seconds < p.band[1]
    # the MAC-count rule, derived from ResNet-18 on its default deployment
    res = published.network_cost(*own.RULE_NETWORK)
    t = fa.compute.predict_latency(res, rock).seconds
    assert rock.overhead_s + res.macs / rock.macs_per_s == pytest.approx(t, rel=1e-9)
    # a drone carrying it: its idle and busy power, the tasks on it
    drone = fa.drone("dji-mavic-2-pro", device=rock)
    assert drone.device == "rock-5b" and drone.computer is rock
    soc = drone.energy.component("proc").component("soc")
    assert (soc.idle_w, soc.active_w) == (1.5, 8.0)
    task = fa.Task(fa.ml.shipped("crowd_cnn"), period_s=1.0, name="cnn", runtime="ncnn")
    r = fa.Mission(drone, fa.pilots.Hover(altitude=5.0, duration=3.0), tasks=[task],
                   seed=0).run()
    assert r.scenario["computers"] == [{"name": "rock-5b", "source": "blueprint"}]
    assert r.kpis["cnn.inference_latency_p50_s"] == pytest.approx(p.seconds, rel=1e-9)
    assert r.kpis["cnn.compute_energy_j"] > 0


def test_based_on_starts_from_a_profile(tmp_path):
    p = tmp_path / "oc.toml"
    p.write_text('[computers.pi5-3ghz]\nbased_on = "raspberry-pi-5"\n'
                 '[computers.pi5-3ghz.cpu]\nclock_ghz = 3.0\n')
    oc = fa.compute.computer(p)
    pi5 = DEVICES["raspberry-pi-5"]
    assert oc.unit("cpu").clock_ghz == 3.0 and pi5.unit("cpu").clock_ghz == 2.4
    assert oc.unit("cpu").peak_macs("fp32") == pytest.approx(pi5.unit("cpu").peak_macs("fp32") * 1.25)
    assert (oc.idle_w, oc.memory_mb, oc.stream_gbs) == (pi5.idle_w, pi5.memory_mb, pi5.stream_gbs)
    # faster, by no more than the clock (the memory-bound layers do not speed up)
    a = fa.compute.predict_latency(CNN, pi5, runtime="ncnn", input_shape=SHAPE).seconds
    b = fa.compute.predict_latency(CNN, oc, runtime="ncnn", input_shape=SHAPE).seconds
    assert a / 1.25 <= b < a


@pytest.mark.parametrize("edit, says", [
    (("cpu", "clock_hz", 2.0), "clock_hz is not a field (did you mean: clock_ghz?)"),
    (("cpu", "clock_ghz", -1.0), "clock_ghz = -1.0 is not allowed; it must be a number > 0"),
    (("cpu", "cores", 2.5), "cores = 2.5 is not allowed; it must be a whole number > 0"),
    (("power", "busy_w", 1.0), "power.busy_w = 1.0 is not allowed; it must be above power.idle_w"),
    (("", "runtimes", ["onnxruntime", "ncn"]), "'ncn' is not a runtime (did you mean: ncnn?)"),
    (("", "runtimes", ["tensorrt"]), "'tensorrt' cannot run on this computer; it needs a [gpu] "
                                     "with cuda_cores"),
    (("", "runtimes", ["edgetpu"]), "'edgetpu' cannot run on this computer; it needs an [npu]"),
    (("", "memory_bandwidth_gbs", None), "memory_bandwidth_gbs is missing"),
    (("power", "idle_w", None), "power.idle_w is missing"),
    (("cpu", "fp32_flop_per_cycle_per_core", None), "fp32_flop_per_cycle_per_core is missing"),
    (("", "name", 3), "name = 3 is not allowed; it must be a string"),
])
def test_a_bad_datasheet_names_the_field_the_value_and_what_is_allowed(tmp_path, edit, says):
    t = tomllib.loads(ROCK)["computers"]["rock-5b"]
    sub, key, value = edit
    tab = t[sub] if sub else t
    if value is None:
        del tab[key]
    else:
        tab[key] = value
    with pytest.raises(ConfigError) as e:
        fa.compute.computer(t, name="rock-5b")
    assert says in str(e.value)
    assert "rock-5b" in str(e.value)


def test_a_bad_source_or_name_is_refused(tmp_path, rock_file):
    with pytest.raises(ConfigError, match="no such file"):
        fa.compute.computer(tmp_path / "none.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[computers\n")
    with pytest.raises(ConfigError, match="is not TOML"):
        fa.compute.computer(bad)
    bad.write_text('[drones.x]\nmass = 1\n')
    with pytest.raises(ConfigError, match=r"no \[computers.NAME\] table"):
        fa.compute.computer(bad)
    with pytest.raises(ConfigError, match="'rock5b' is not a computer of boards.toml "
                                          r"\(did you mean: rock-5b\?\)"):
        fa.compute.computer(rock_file, "rock5b")
    two = tmp_path / "two.toml"
    two.write_text(ROCK + ROCK.replace("rock-5b", "rock-5c"))
    with pytest.raises(ConfigError, match="holds 2 computers"):
        fa.compute.computer(two)
    assert fa.compute.computer(two, "rock-5c").name == "rock-5c"
    with pytest.raises(ConfigError, match="is a profile of the package"):
        fa.compute.computer(builtin("raspberry-pi-4"), name="raspberry-pi-4")
    with pytest.raises(ConfigError, match="based_on = 'raspberry-pi-6' is not a profile"):
        fa.compute.computer({"based_on": "raspberry-pi-6"}, name="x")
    with pytest.raises(ConfigError, match="needs name="):
        fa.compute.computer(builtin("raspberry-pi-4"))
    with pytest.raises(ConfigError, match="is not a datasheet"):
        fa.compute.computer(42)


def test_the_packages_own_datasheets_pass_the_same_schema():
    """A misspelt field in computers.toml would be dropped silently; it is a ConfigError."""
    from pytest_flockai.compute import datasheets
    t = builtin("jetson-orin-nano")
    datasheets.check("jetson-orin-nano", t, "computers.toml")
    t["gpu"] = {**t["gpu"], "fp16_tensor_tflop": 1.0}
    with pytest.raises(ConfigError, match=r"\[computers.jetson-orin-nano.gpu\] fp16_tensor_tflop "
                                          r"is not a field \(did you mean: fp16_tensor_tflops"):
        datasheets.check("jetson-orin-nano", t, "computers.toml")


def test_cuda_runtimes_need_an_nvidia_gpu():
    """A GPU without cuda_cores runs ncnn's Vulkan, not TensorRT or ONNX Runtime's CUDA."""
    t = tomllib.loads(ROCK)["computers"]["rock-5b"]
    t["gpu"] = {"clock_ghz": 1.0, "fp32_tflops": 0.45, "fp16_tflops": 0.9}
    t["runtimes"] = ["onnxruntime", "ncnn"]
    dev = fa.compute.computer(t, name="rock-gpu")
    assert dev.deployments == ("onnxruntime/cpu", "ncnn/cpu", "ncnn/gpu")
    assert fa.compute.predict_latency(CNN, dev, input_shape=SHAPE).target == "cpu"


def test_a_drone_carries_the_computer_its_device_names():
    """``fa.drone(name, device=...)`` and a later ``drone.device = ...`` (a sweep's device
    axis) put that computer's idle and busy power in the energy model; before, the
    blueprint's computer stayed in it and only the latency moved."""
    def fly(d):
        return fa.Mission(d, fa.pilots.Hover(altitude=5.0, duration=4.0), seed=0).run()
    pi = fly(fa.drone("dji-mavic-2-pro"))                   # the blueprint's Raspberry Pi 4
    orin = fa.drone("dji-mavic-2-pro", device="jetson-orin-nano")
    soc = orin.energy.component("proc").component("soc")
    assert (soc.idle_w, soc.active_w) == (DEVICES["jetson-orin-nano"].idle_w,
                                          DEVICES["jetson-orin-nano"].active_w)
    jet = fly(orin)
    t = jet.scenario["sim_time_s"]
    d_idle = DEVICES["jetson-orin-nano"].idle_w - DEVICES["raspberry-pi-4"].idle_w
    assert jet.kpis["energy_proc_j"] - pi.kpis["energy_proc_j"] == pytest.approx(d_idle * t, rel=0.02)
    later = fa.drone("dji-mavic-2-pro")
    later.device = "jetson-orin-nano"
    assert fly(later).kpis == jet.kpis
    later.device = "none"
    assert "soc" not in later.energy.component("proc") and later.computer is None
    with pytest.raises(ConfigError, match="device = 'jetson-orin-nan'.*did you mean"):
        later.device = "jetson-orin-nan"
    with pytest.raises(ConfigError, match="is not a device"):
        later.device = 3


def test_the_cli_adds_your_computers(rock_file, tmp_path, capsys):
    from pytest_flockai.cli import main
    out = tmp_path / "rows.json"
    assert main(["predict-latency", str(CNN), "--input-shape", "1x3x240x320", "--computers",
                 str(rock_file), "--computer", "rock-5b", "--computer", "raspberry-pi-5",
                 "--json", str(out)]) == 0
    rows = json.loads(out.read_text())["rows"]
    assert {r["computer"] for r in rows} == {"rock-5b", "raspberry-pi-5"}
    rock = fa.compute.computer(rock_file)
    for r in rows:
        if r["computer"] == "rock-5b":
            p = fa.compute.predict_latency(CNN, rock, runtime=r["runtime"], input_shape=SHAPE)
            assert r["seconds"] == pytest.approx(p.seconds)
    assert main(["predict-latency", str(CNN), "--computers", str(rock_file), "--computer",
                 "rock5b"]) == 2
    assert "--computer = 'rock5b'" in capsys.readouterr().err
