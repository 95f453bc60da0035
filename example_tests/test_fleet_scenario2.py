"""The paper's scenario 2 (the CNN on the ground station) flown by a fleet of 1, 2,
4 and 8 Mavics over the city, each surveying its own strip of the area
(issue 14): where the shared radio channel and the ground GPU saturate.

The drones carry no camera in a fleet yet, so each frame is the offload model's
(``fa.fleet.Offload``): the size of scenario 2's JPEG-90 frames of the 320x240
camera (about 5.2 kB: the ``tx_bytes`` of its inference events), the CNN's
525.6 M MACs on the ground GPU, a 256-byte result, a frame every 5 s
(the paper's inf_period=5), over 802.11n and over the 64 kbit/s telemetry radio
(scenario "2-slow"). Pads are 25 m west of the city's survey box, clear of its
buildings.
"""

import pytest

import pytest_flockai as fa

AREA = ((-100.0, -100.0), (100.0, 100.0))
SIZES = (1, 2, 4, 8)
FRAME_BYTES, RESULT_BYTES, CNN_MACS = 5200, 256, 525.6e6     # see the module docstring
_RESULTS: dict = {}


def fleet(n: int, link: str, city) -> fa.FleetResult:
    key = (n, link)
    if key not in _RESULTS:
        parts = fa.fleet.survey(AREA, n, altitude=35.0, spacing=12.5, speed=8.0, pad_offset_m=25.0)
        off = fa.fleet.Offload(period_s=5.0, frame_bytes=FRAME_BYTES, result_bytes=RESULT_BYTES,
                               macs=CNN_MACS, link=link, ground_station=(-125.0, 0.0, 1.0))
        _RESULTS[key] = fa.Fleet([fa.FleetDrone(f"drone-{i + 1}", fa.drone("dji-mavic-2-pro"), p,
                                                pad=pad, seed=i) for i, (p, pad) in enumerate(parts)],
                                 world=city, area=AREA, swath_m=12.5, offload=off).run()
    return _RESULTS[key]


@pytest.mark.kpi({"fleet.crashes": "== 0", "fleet.coverage_fraction": ">= 95%",
                  "fleet.min_separation_m": ">= 5 m"})
@pytest.mark.parametrize("n", SIZES)
def test_scenario_2_fleet_over_wifi(n, city):
    r = fleet(n, "wifi-80211n", city)
    assert r.kpis["offload.latency_p95_s"] <= 0.1                 # 802.11n never saturates here


@pytest.mark.kpi({"fleet.crashes": "== 0", "fleet.coverage_fraction": ">= 95%"})
@pytest.mark.parametrize("n", SIZES)
def test_scenario_2_fleet_over_the_telemetry_radio(n, city):
    fleet(n, "sik-915", city)


def test_where_the_shared_channel_saturates(city):
    """The drones' cameras fire together, so even Wi-Fi frames wait for each other (tens
    of ms). Four drones share the 64 kbit/s radio within its capacity (about 0.9 s of
    airtime per 5 s frame each: p95 grows with the queue of one period); eight need 7 s
    of airtime every 5 s, and their frames pile up all flight (p95 well above the period)."""
    wifi = [fleet(n, "wifi-80211n", city).kpis for n in SIZES]
    slow = [fleet(n, "sik-915", city).kpis for n in SIZES]
    for n, w, s in zip(SIZES, wifi, slow):
        print(f"{n} drones: makespan {w['fleet.makespan_s']:.0f} s; offload p95 "
              f"Wi-Fi {w['offload.latency_p95_s']:.3f} s, 64 kbit/s {s['offload.latency_p95_s']:.2f} s "
              f"(channel wait p95 {s['link.queue_delay_p95_s']:.2f} s); ground GPU "
              f"{100 * w['ground.utilization']:.3f} % busy")
    p95_wifi = [w["offload.latency_p95_s"] for w in wifi]
    p95_slow = [s["offload.latency_p95_s"] for s in slow]
    assert all(a < b for a, b in zip(p95_wifi, p95_wifi[1:])) and p95_wifi[-1] < 0.1
    assert all(a < b for a, b in zip(p95_slow, p95_slow[1:]))
    assert p95_slow[2] < 5.0 < p95_slow[3]                       # 4 fit in a period, 8 do not
    assert all(w["ground.utilization"] < 0.01 for w in wifi)       # the ground GPU is far from it
