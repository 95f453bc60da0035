"""Radio links between the drone and the ground station.

A ``Link`` turns "send n bytes over d metres" into time, packets and
retransmissions, with every random draw from the generator passed in::

    wifi = link("wifi-80211n")
    tr = wifi.transfer(120_000, distance_m=80.0, rng=np.random.default_rng(0))
    tr.seconds, tr.packets, tr.retransmissions, tr.bytes_on_air

Model (per transfer):

- received power from a log-distance path-loss model (Rappaport, *Wireless
  Communications*, 2nd ed., eq. 4.68):
  ``P_rx = P_tx + G - FSPL(d0) - 10 n log10(d / d0)``, ``FSPL(1 m) = 20 log10(4 pi / lambda)``;
- the PHY rate is the highest rate of the link's table whose receiver
  sensitivity ``P_rx`` meets (rate adaptation); below the lowest sensitivity the
  link is down and the transfer is not delivered (``delivered=False``);
- payload split into packets of ``payload_per_packet`` bytes plus
  ``header_bytes`` on air each; each attempt is lost with probability
  ``loss = loss_floor + 0.5 * 10^(-margin_dB / 10)`` (margin over the lowest
  sensitivity; the 0.5 at zero margin is a modelling choice, not a measured
  figure); attempts per packet are geometric (drawn from ``rng``); beyond
  ``retry_limit`` retries the transport layer's timeout ``rto_s`` is added;
- time = one-way ``latency_s`` + jitter (exponential, mean ``jitter_s``) +
  airtime (bytes on air / PHY rate + ``per_packet_s`` per attempt for
  contention, preamble and acknowledgement) + ``retry_penalty_s`` per
  retransmission (summed for a contention MAC like 802.11; only the longest
  chain counts for a scheduled MAC with parallel HARQ processes like LTE).

Links with ``fixed_rate=True`` (cellular) ignore distance: the drone talks to
a cell tower, not to the ground station.

Energy: each profile carries power states (``tx_w``, ``rx_w``, ``idle_w``)
and, for Wi-Fi, the Feeney-Nilsson per-byte / per-packet figures;
``radio_component()`` makes the matching energy component.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, replace

import numpy as np

from ..energy.components import RadioLinear, RadioStates
from ..errors import ConfigError, close_matches

C_LIGHT = 299_792_458.0


@dataclass(frozen=True)
class Transfer:
    """The result of sending one message over a link."""

    seconds: float          # from the first bit handed to the radio to the last delivered
    packets: int            # transmissions on air, retransmissions included
    retransmissions: int
    bytes_on_air: int       # payload + headers, retransmissions included
    payload_bytes: int      # payload bytes transmitted, retransmissions included
    delivered: bool = True
    rate_bps: float = 0.0   # PHY rate used

    def to_dict(self) -> dict:
        """The fields as a JSON-ready dict."""
        return asdict(self)


@dataclass(frozen=True)
class Link:
    """A radio link profile; build your own for other radios."""

    name: str
    rates: tuple                       # ((sensitivity_dbm, phy_rate_bps), ...) ascending rate
    tx_power_dbm: float = 20.0
    antenna_gain_db: float = 0.0       # sum of both ends' gains
    frequency_hz: float = 2.437e9
    path_loss_exponent: float = 2.2
    ref_distance_m: float = 1.0
    fixed_rate: bool = False           # cellular: rate independent of the ground-station distance
    down_rate_scale: float = 1.0       # downlink rate = uplink rate * this
    payload_per_packet: int = 1460     # TCP MSS over a 1500-byte MTU
    header_bytes: int = 82             # 802.11 MAC header + FCS 34, LLC/SNAP 8, IPv4 20, TCP 20
    per_packet_s: float = 170e-6       # DIFS + mean backoff + preamble + SIFS + ACK
    latency_s: float = 1e-3            # one-way base latency (stacks, access point)
    jitter_s: float = 1e-3             # mean of the exponential jitter
    loss_floor: float = 0.01           # per-attempt loss with a strong signal
    retry_limit: int = 7               # link-layer retries before giving up
    retry_penalty_s: float = 0.2e-3    # extra time per retransmission (backoff)
    parallel_retries: bool = False     # True: retransmissions overlap (HARQ)
    rto_s: float = 0.2                 # transport retransmission timeout
    timeout_s: float = 2.0             # time lost when the link is down
    tx_w: float = 8.4
    rx_w: float = 8.4
    idle_w: float = 4.2
    tx_uj_per_byte: float | None = None
    tx_uj_per_packet: float | None = None
    rx_uj_per_byte: float | None = None
    rx_uj_per_packet: float | None = None
    source: str = ""
    notes: dict = field(default_factory=dict, compare=False)

    def __post_init__(self):
        w = f"link {self.name!r}"
        if not self.rates:
            raise ConfigError(f"{w}: rates = {self.rates!r} is empty; expected ((sensitivity_dbm, bps), ...)")
        for s, r in self.rates:
            if not (math.isfinite(s) and r > 0):
                raise ConfigError(f"{w}: rates entry ({s!r}, {r!r}) is not allowed; expected a finite "
                                  f"sensitivity in dBm and a rate > 0 bit/s")
        for f in ("payload_per_packet",):
            if getattr(self, f) <= 0:
                raise ConfigError(f"{w}: {f} = {getattr(self, f)!r} must be > 0")
        for f in ("latency_s", "jitter_s", "per_packet_s", "retry_penalty_s", "rto_s", "timeout_s",
                  "header_bytes", "tx_w", "rx_w", "idle_w"):
            if not getattr(self, f) >= 0:
                raise ConfigError(f"{w}: {f} = {getattr(self, f)!r} must be >= 0")
        if not 0.0 <= self.loss_floor < 1.0:
            raise ConfigError(f"{w}: loss_floor = {self.loss_floor!r} is out of range; allowed: 0 .. < 1")
        if self.path_loss_exponent <= 0 or self.ref_distance_m <= 0 or self.frequency_hz <= 0:
            raise ConfigError(f"{w}: path_loss_exponent, ref_distance_m and frequency_hz must be > 0")

    # -- radio ---------------------------------------------------------------
    def rx_power_dbm(self, distance_m: float) -> float:
        """Received power (dBm) at ``distance_m``: log-distance path loss from the
        free-space loss at ``ref_distance_m`` (closer than that counts as that)."""
        lam = C_LIGHT / self.frequency_hz
        d0 = self.ref_distance_m
        fspl0 = 20.0 * math.log10(4.0 * math.pi * d0 / lam)
        d = max(float(distance_m), d0)
        return (self.tx_power_dbm + self.antenna_gain_db - fspl0
                - 10.0 * self.path_loss_exponent * math.log10(d / d0))

    def margin_db(self, distance_m: float) -> float:
        """Received power over the lowest sensitivity (the link edge)."""
        if self.fixed_rate:
            return math.inf
        return self.rx_power_dbm(distance_m) - min(s for s, _ in self.rates)

    def phy_rate(self, distance_m: float, direction: str = "up") -> float:
        """PHY bit rate at this distance (0 when out of range)."""
        if self.fixed_rate:
            r = max(r for _, r in self.rates)
        else:
            p = self.rx_power_dbm(distance_m)
            ok = [r for s, r in self.rates if p >= s]
            r = max(ok) if ok else 0.0
        return r * (self.down_rate_scale if direction == "down" else 1.0)

    def loss_probability(self, distance_m: float) -> float:
        """Probability that one packet is lost at ``distance_m``: ``loss_floor`` plus a
        term growing as the margin shrinks, at most 0.95."""
        m = self.margin_db(distance_m)
        if not math.isfinite(m):
            return self.loss_floor
        return min(0.95, self.loss_floor + 0.5 * 10.0 ** (-m / 10.0))

    def range_m(self) -> float:
        """Distance at which the link goes down (inf for fixed-rate links)."""
        if self.fixed_rate:
            return math.inf
        lam = C_LIGHT / self.frequency_hz
        fspl0 = 20.0 * math.log10(4.0 * math.pi * self.ref_distance_m / lam)
        budget = self.tx_power_dbm + self.antenna_gain_db - fspl0 - min(s for s, _ in self.rates)
        return self.ref_distance_m * 10.0 ** (budget / (10.0 * self.path_loss_exponent))

    # -- transfers -------------------------------------------------------------
    def transfer(self, n_bytes: int, distance_m: float, rng: np.random.Generator, *,
                 direction: str = "up") -> Transfer:
        """Send ``n_bytes`` over ``distance_m``; draws loss and jitter from ``rng``."""
        if direction not in ("up", "down"):
            raise ConfigError(f"direction = {direction!r} is not allowed; allowed: 'up', 'down'")
        n = int(n_bytes)
        if n < 0:
            raise ConfigError(f"n_bytes = {n_bytes!r} must be >= 0")
        if n == 0:
            return Transfer(0.0, 0, 0, 0, 0, True, 0.0)
        rate = self.phy_rate(distance_m, direction)
        if rate <= 0.0:
            return Transfer(self.timeout_s, 0, 0, 0, 0, False, 0.0)
        mss = self.payload_per_packet
        packets = -(-n // mss)
        p = self.loss_probability(distance_m)
        attempts = rng.geometric(1.0 - p, size=packets) if p > 0.0 else np.ones(packets, np.int64)
        jitter = rng.exponential(self.jitter_s) if self.jitter_s > 0.0 else 0.0
        tx = int(attempts.sum())
        retrans = tx - packets
        last = n - (packets - 1) * mss
        payload = int((attempts[:-1].sum() * mss if packets > 1 else 0) + attempts[-1] * last)
        on_air = payload + tx * self.header_bytes
        per_chain = self.retry_limit + 1
        rto_rounds = int(((attempts - 1) // per_chain).sum())
        if self.parallel_retries:
            penalty = (int(attempts.max()) - 1) * self.retry_penalty_s
        else:
            penalty = retrans * self.retry_penalty_s
        seconds = (self.latency_s + jitter + on_air * 8.0 / rate + tx * self.per_packet_s
                   + penalty + rto_rounds * self.rto_s)
        return Transfer(float(seconds), tx, retrans, int(on_air), payload, True, float(rate))

    # -- energy ----------------------------------------------------------------
    def radio_component(self, name: str = "radio", *, model: str = "states"):
        """An energy component for this radio: ``"states"`` (paper's P_x t_x +
        P_r t_r + P_idle t_idle at the link's top rate) or ``"linear"``
        (Feeney-Nilsson per byte / per packet, Wi-Fi only)."""
        if model == "states":
            return RadioStates(name, tx_w=self.tx_w, rx_w=self.rx_w, idle_w=self.idle_w,
                               bitrate_bps=max(r for _, r in self.rates),
                               description=f"{self.name}: power states ({self.source})")
        if model == "linear":
            if self.tx_uj_per_byte is None:
                raise ConfigError(f"link {self.name!r} has no per-byte energy figures; "
                                  f"use model='states'")
            return RadioLinear(name, tx_uj_per_byte=self.tx_uj_per_byte,
                               tx_uj_per_packet=self.tx_uj_per_packet,
                               rx_uj_per_byte=self.rx_uj_per_byte,
                               rx_uj_per_packet=self.rx_uj_per_packet, idle_w=self.idle_w,
                               description=f"{self.name}: Feeney-Nilsson linear model")
        raise ConfigError(f"model = {model!r} is not allowed; allowed: 'states', 'linear'")

    def with_(self, **changes) -> Link:
        """A copy with some fields changed (e.g. ``loss_floor=0.0`` in tests)."""
        return replace(self, **changes)

    def to_dict(self) -> dict:
        """The profile as a JSON-ready dict (without ``notes``)."""
        d = asdict(self)
        d["rates"] = [list(r) for r in self.rates]
        d.pop("notes", None)
        return d


# IEEE Std 802.11n-2009: HT MCS 0-7, one spatial stream, 20 MHz, 800 ns guard
# interval: 6.5 ... 65 Mbit/s (MCS table, clause 20.6); receiver minimum input
# sensitivity -82 ... -64 dBm for those MCS (clause 20.3.21.1, Table 20-22).
_HT20_1SS = ((-82.0, 6.5e6), (-79.0, 13.0e6), (-77.0, 19.5e6), (-74.0, 26.0e6),
             (-70.0, 39.0e6), (-66.0, 52.0e6), (-65.0, 58.5e6), (-64.0, 65.0e6))

LINKS: dict[str, Link] = {lk.name: lk for lk in (
    Link(
        "wifi-80211n", rates=_HT20_1SS,
        # 20 dBm EIRP: the 2.4 GHz limit in Europe (ETSI EN 300 328); channel 6.
        tx_power_dbm=20.0, antenna_gain_db=0.0, frequency_hz=2.437e9,
        # between free space (2.0) and what low-altitude air-to-ground 802.11
        # measurements report (about 2-2.5, e.g. Yanmaz et al., IEEE INFOCOM 2013) (check)
        path_loss_exponent=2.2,
        # 802.11n 2.4 GHz timing: SIFS 10 us, slot 9 us, DIFS 28 us, mean backoff
        # CWmin 15 -> 67.5 us, HT-mixed preamble ~36 us, ACK ~28 us: ~170 us per frame
        per_packet_s=170e-6, latency_s=1e-3, jitter_s=1e-3, loss_floor=0.01,
        retry_limit=7,              # dot11ShortRetryLimit default
        retry_penalty_s=0.2e-3, rto_s=0.2,    # Linux TCP_RTO_MIN 200 ms
        # power states: the FlockAI paper's Wi-Fi, 8.4 W tx/rx, 4.2 W idle (the FlockAI project's released energy model)
        tx_w=8.4, rx_w=8.4, idle_w=4.2,
        # Feeney and Nilsson, IEEE INFOCOM 2001: E = m * bytes + b per packet
        tx_uj_per_byte=1.9, tx_uj_per_packet=420.0, rx_uj_per_byte=0.42, rx_uj_per_packet=330.0,
        source="IEEE 802.11n-2009 HT20 1SS MCS0-7 rates and sensitivities; log-distance path "
               "loss; FlockAI paper Wi-Fi powers; Feeney-Nilsson 2001"),
    Link(
        "lte", rates=((-100.0, 5.64e6),), fixed_rate=True,   # sensitivity unused (fixed rate)
        # median LTE throughput measured by Huang et al., "A Close Examination of
        # Performance and Power Characteristics of 4G LTE Networks", MobiSys 2012:
        # uplink 5.64 Mbit/s, downlink 12.74 Mbit/s (check)
        down_rate_scale=12.74 / 5.64,
        header_bytes=45,            # IPv4 20 + TCP 20 + PDCP/RLC/MAC ~5
        per_packet_s=0.0,           # scheduled access: no contention per packet
        latency_s=0.035, jitter_s=0.005,   # ~70 ms RTT (Huang et al. 2012) (check)
        # HARQ: 10 % block error target on the first transmission, 8 ms HARQ RTT
        # (FDD), up to 4 transmissions, retransmissions in parallel processes
        loss_floor=0.10, retry_limit=3, retry_penalty_s=8e-3, parallel_retries=True,
        rto_s=0.04,                 # RLC ARQ recovery (assumed)
        # Huang et al. 2012 power model: P = 438.39 mW/Mbps * up + 51.97 mW/Mbps * down
        # + 1288.04 mW; at the median rates: up 3.76 W, down 1.95 W; tail/idle while
        # connected ~1.06 W (check)
        tx_w=3.76, rx_w=1.95, idle_w=1.06,
        source="Huang et al. MobiSys 2012 (LTE throughput, RTT, power model); 3GPP HARQ"),
    Link(
        "sik-915", rates=((-106.0, 64.0e3),),
        # the 3DR/ArduPilot SiK telemetry radio (HopeRF RFM26W, 915 MHz): default
        # air data rate 64 kbit/s, 20 dBm transmit power (ArduPilot "SiK Telemetry
        # Radio" documentation); sensitivity at 64 kbit/s about -106 dBm (RFM26W /
        # Si4463 data sheet curves) (check). Frames of at most 252 bytes, TDM
        # duplex, so the downlink shares the air time.
        tx_power_dbm=20.0, frequency_hz=915e6, path_loss_exponent=2.2,
        payload_per_packet=252, header_bytes=13, per_packet_s=4e-3, latency_s=0.03,
        jitter_s=0.01, loss_floor=0.02, retry_limit=3, retry_penalty_s=10e-3, rto_s=0.5,
        # ~100 mA at 5 V transmitting at 20 dBm, ~25 mA receiving (SiK docs / RFM26W) (check)
        tx_w=0.5, rx_w=0.12, idle_w=0.12,
        source="ArduPilot SiK telemetry radio documentation; HopeRF RFM26W / Si4463 data sheet"),
)}


def links() -> list[str]:
    """Names of the built-in link profiles."""
    return sorted(LINKS)


def link(name: str | Link) -> Link:
    """A link profile by name (or a ``Link`` passed through)."""
    if isinstance(name, Link):
        return name
    try:
        return LINKS[name]
    except (KeyError, TypeError):
        raise ConfigError(f"link = {name!r} is not a known link{close_matches(str(name), LINKS)}; "
                          f"available: {', '.join(links())}") from None


__all__ = ["LINKS", "Link", "Transfer", "link", "links"]
