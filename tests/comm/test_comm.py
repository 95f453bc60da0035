"""Radio link model: rates over distance, seeded loss and retransmission."""

import math

import numpy as np
import pytest

from pytest_flockai.comm import Link, link, links
from pytest_flockai.energy.components import RadioLinear, RadioStates
from pytest_flockai.errors import ConfigError


def test_builtin_links_and_unknown_name():
    assert {"wifi-80211n", "lte"} <= set(links())
    with pytest.raises(ConfigError, match=r"wifi-80211n"):
        link("wifi-80211")
    with pytest.raises(ConfigError, match="available"):
        link("carrier-pigeon")


def test_wifi_rate_falls_with_distance_and_link_goes_down():
    w = link("wifi-80211n")
    rates = [w.phy_rate(d) for d in (5, 50, 150, 300, 500, 640)]
    assert rates[0] == 65e6
    assert all(a >= b for a, b in zip(rates, rates[1:])) and rates[-1] == 6.5e6
    assert 500 < w.range_m() < 800
    tr = w.transfer(10_000, w.range_m() * 1.1, np.random.default_rng(0))
    assert not tr.delivered and tr.packets == 0
    assert w.loss_probability(600) > w.loss_probability(50)


def test_transfer_accounting_without_loss():
    w = link("wifi-80211n").with_(loss_floor=0.0, jitter_s=0.0)
    n = 10_000
    tr = w.transfer(n, 1.0, np.random.default_rng(0))   # at 1 m the margin term is ~1e-6
    packets = math.ceil(n / 1460)
    assert w.loss_probability(1.0) < 1e-6
    assert tr.retransmissions == 0 and tr.packets == packets
    assert tr.payload_bytes == n
    assert tr.bytes_on_air == n + packets * w.header_bytes
    want = w.latency_s + tr.bytes_on_air * 8 / 65e6 + packets * w.per_packet_s
    assert tr.seconds == pytest.approx(want)
    assert w.transfer(0, 10.0, np.random.default_rng(0)).seconds == 0.0


def test_loss_and_retransmission_reproducible_from_seed():
    w = link("wifi-80211n")
    a = [w.transfer(200_000, 550.0, np.random.default_rng(7)) for _ in range(2)]
    assert a[0] == a[1]
    assert a[0].retransmissions > 0
    assert a[0].payload_bytes > 200_000 and a[0].packets == 137 + a[0].retransmissions
    others = {w.transfer(200_000, 550.0, np.random.default_rng(s)).retransmissions for s in range(6)}
    assert len(others) > 1            # the draws do come from the rng
    near = w.transfer(200_000, 20.0, np.random.default_rng(7))
    assert near.seconds < a[0].seconds and near.retransmissions < a[0].retransmissions


def test_lte_ignores_distance_and_is_slower_than_close_wifi():
    lte = link("lte")
    r = np.random.default_rng(1)
    assert lte.phy_rate(10) == lte.phy_rate(5000) and lte.range_m() == math.inf
    assert lte.phy_rate(10, "down") > lte.phy_rate(10, "up")
    t_lte = lte.transfer(100_000, 5000.0, r)
    t_wifi = link("wifi-80211n").transfer(100_000, 30.0, np.random.default_rng(1))
    assert t_lte.delivered and t_lte.seconds > t_wifi.seconds


def test_custom_link_validation_and_energy_components():
    with pytest.raises(ConfigError, match="loss_floor"):
        Link("bad", rates=((-80.0, 1e6),), loss_floor=1.5)
    with pytest.raises(ConfigError, match="rates"):
        Link("bad", rates=())
    w = link("wifi-80211n")
    states = w.radio_component()
    assert isinstance(states, RadioStates) and states.tx_w == 8.4 and states.idle_w == 4.2
    lin = w.radio_component(model="linear")
    assert isinstance(lin, RadioLinear) and lin.tx_uj_per_byte == 1.9
    with pytest.raises(ConfigError):
        link("lte").radio_component(model="linear")
