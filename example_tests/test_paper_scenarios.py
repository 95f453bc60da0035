"""The FlockAI paper's Table 2 scenarios as KPI-gated tests, and its four
questions (section 2) as assertions across scenarios.

Run: ``pytest example_tests -n 2 --flockai-json kpis.json`` (short surveys,
``endurance_s`` budgets), or add ``--flockai-full`` to fly every scenario
until the battery is depleted as the paper did. ``python example_tests/paper_table.py``
prints our figures next to the paper's, with the reasons they differ.
"""

import pytest


# measured (session 7, short surveys): 1-A and 2 / 2-slow / 3-B 31.6 min, 1-B 31.6 min (30.5 and
# 30.4 while the Mavic's motor efficiency was fitted to DJI's hover time): budgets 2.5-3.5 min below
@pytest.mark.kpi(endurance_s=">= 29 min", energy_share_motors=">= 85%", energy_share_comm="< 3%",
                 crashed="== 0", tracking_error_max_m="<= 1.5 m")
def test_1a_no_ml(sc_1a):
    assert sc_1a.end_reason in ("landed", "battery_depleted")


@pytest.mark.kpi(endurance_s=">= 28 min", inference_latency_p50_s="<= 1.5 s", frames_dropped="== 0",
                 energy_share_proc="< 25%", crashed="== 0")
def test_1b_cnn_on_board(sc_1b):
    assert sc_1b.kpis["inference_count"] >= 10


@pytest.mark.kpi(endurance_s=">= 28 min", inference_latency_p50_s="<= 1.5 s", crashed="== 0")
def test_2_cnn_remote_over_wifi(sc_2):
    assert sc_2.kpis["kbytes_out"] > 0


@pytest.mark.kpi(endurance_s=">= 28 min", crashed="== 0")
def test_2_cnn_remote_over_a_slow_radio(sc_2slow):
    assert sc_2slow.kpis["inference_count"] >= 5


@pytest.mark.kpi(endurance_s=">= 28 min", inference_latency_p50_s="<= 0.3 s", crashed="== 0")
def test_3b_cheaper_model_on_board(sc_3b):
    assert sc_3b.kpis["inference_count"] >= 10


# -- the paper's questions -------------------------------------------------------------

def test_q1_model_runs_in_time_on_the_drone(sc_1b):
    """Q1: on a Raspberry Pi 4 the CNN finishes well within the 5 s camera period."""
    k = sc_1b.kpis
    assert k["inference_latency_max_s"] < 5.0 and k["frames_dropped"] == 0


def test_q2_ml_costs_energy_and_flight_time(sc_1a, sc_1b):
    """Q2: on-board inference costs processing energy and so flight time."""
    a, b = sc_1a.kpis, sc_1b.kpis
    assert b["energy_share_proc"] > a["energy_share_proc"]
    assert b["endurance_s"] < a["endurance_s"]
    assert sc_1b.energy_breakdown["proc.soc.active"] > 0 == sc_1a.energy_breakdown["proc.soc.active"]


def test_q3_remote_saves_flight_time_but_latency_depends_on_the_link(sc_1b, sc_2, sc_2slow):
    """Q3: offloading moves the cost from processing to communication and saves
    flight time; over the paper's slow path the answer comes later than on
    board (paper: 3.15 s vs 1.36 s), over a good Wi-Fi link sooner."""
    onb, wifi, slow = sc_1b.kpis, sc_2.kpis, sc_2slow.kpis
    assert wifi["endurance_s"] > onb["endurance_s"]
    assert wifi["energy_proc_j"] < onb["energy_proc_j"]
    assert wifi["kbytes_out"] > onb["kbytes_out"] and wifi["energy_comm_j"] > onb["energy_comm_j"]
    assert slow["inference_latency_p50_s"] > onb["inference_latency_p50_s"]
    assert wifi["inference_latency_p50_s"] < onb["inference_latency_p50_s"]


def test_q4_cheaper_model_flies_longer_and_counts_worse(sc_1b, sc_3b):
    """Q4: the cheaper model is faster and flies longer, but counts worse."""
    cnn, cheap = sc_1b.kpis, sc_3b.kpis
    # the CNN's latency is the layer model's (ONNX Runtime on the Pi 4, ~31 ms); the blob
    # counter's the MAC-count rule's (10 ms overhead + 2.3 M MAC-equivalents, ~12 ms)
    assert cheap["inference_latency_p50_s"] < cnn["inference_latency_p50_s"] / 2
    assert cheap["endurance_s"] > cnn["endurance_s"]
    assert cheap["count_mae"] > cnn["count_mae"]
