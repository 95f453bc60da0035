"""Beyond the paper: a person + vehicle detector (fixtures/models/detector.onnx)
flown over the city with cars, scored against the simulator's per-object truth
by the COCO standard, on board a Raspberry Pi 4, on board a Jetson Orin Nano,
and on the ground station over Wi-Fi. The same questions as the paper's, for
a detector: does it keep up (Q1), what does it cost (Q2), where should it run
(Q3), and how well does it find people and cars, at which altitudes and sizes."""

import pytest

# Budgets about 10 % under what the shipped detector (trained on the articulated figures)
# scores in these flights: map50 0.60 and recall 0.75 on board (vehicles 0.80), map50 0.46
# from JPEG frames on the ground (fixtures/models/README.md).


@pytest.mark.kpi(map50=">= 0.55", recall=">= 0.7", inference_latency_p50_s="<= 0.5 s",
                 frames_dropped="== 0", crashed="== 0", **{"recall.vehicle": ">= 0.72"})
def test_detector_on_board_a_pi4(det_pi4):
    assert det_pi4.kpis["inference_count"] >= 60


@pytest.mark.kpi(map50=">= 0.55", recall=">= 0.7", inference_latency_p50_s="<= 0.05 s")
def test_detector_on_board_a_jetson(det_jetson):
    assert det_jetson.kpis["inference_count"] >= 60


@pytest.mark.kpi(map50=">= 0.42", inference_latency_p50_s="<= 0.2 s", crashed="== 0")
def test_detector_on_the_ground_over_wifi(det_remote):
    assert det_remote.kpis["kbytes_out"] > 100


def test_the_same_detector_finds_the_same_objects_wherever_it_runs(det_pi4, det_jetson):
    """Scoring is a property of the model and the frames: on board, the device
    changes the latency and the energy, not what the detector finds."""
    a, b = det_pi4.kpis, det_jetson.kpis
    assert a["map50"] == pytest.approx(b["map50"])
    # the Pi 4 (ONNX Runtime, 12.8 ms) against the Orin Nano (TensorRT fp16, 2.7 ms)
    assert a["inference_latency_p50_s"] > 4 * b["inference_latency_p50_s"]


def test_offloading_trades_jpeg_accuracy_for_processing_energy(det_pi4, det_remote):
    """Q3 for a detector: remote frames travel as JPEG (quality 90), which costs
    the small objects some accuracy; the drone's computer idles instead."""
    onb, rem = det_pi4.kpis, det_remote.kpis
    assert rem["energy_proc_j"] < onb["energy_proc_j"]
    assert rem["energy_comm_j"] > onb["energy_comm_j"]
    assert rem["map50"] <= onb["map50"] + 0.02


def test_recall_is_reported_by_altitude_band_and_object_size(det_pi4):
    k = det_pi4.kpis
    assert "recall.alt_20_40m" in k
    sizes = [n for n in k if n.startswith("recall.size_")]
    assert len(sizes) >= 2
    # people a few pixels tall are the hard case: never easier than the cars
    assert k["recall.person"] <= k["recall.vehicle"]
