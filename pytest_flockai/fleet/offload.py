"""Remote inference offload of a fleet: one ground station, one radio channel.

``Offload(...)`` given to ``Fleet(offload=...)``: every ``period_s`` each drone
flying its pilot's plan sends a frame of ``frame_bytes`` to the ground
station, whose ground device (``compute.device``) runs one inference of
``macs`` per frame and sends ``result_bytes`` back. Times come from the
project's models: the radio from ``comm.Link.transfer`` (path loss, rate
adaptation, losses; its random draws from the drone's seeded generator), the
inference from ``compute.predict_latency`` when ``model`` (an ONNX path or ``OnnxModel``)
is given, for the ground device's ``runtime``/``precision`` (defaults: its first listed
runtime), else from the ground device's MAC-count rule for ``macs``.

Contention (``shared_link=True``): the drones share one channel, which carries
one uplink at a time (a single FIFO server); the senders of one period are
served round-robin, starting one drone later each period, so in the long run
each of N saturated senders gets 1/N of the airtime: the long-term fairness of
802.11 DCF among N saturated stations (G. Bianchi, "Performance analysis of the
IEEE 802.11 distributed coordination function", IEEE JSAC 18(3), 2000, where
every station has the same transmission probability tau per slot).
Backoff slots and collisions are not modelled beyond the link's own
``per_packet_s`` and retransmissions. ``shared_link=False``: each drone has its
own channel (no contention). The ground device is one FIFO server shared by
all drones, in order of the frames' arrival (the channel and the device are an
``ml.events.SharedGround``, the queues the fleet's remote ``Task``s use too). The
small downlink results are not queued on the channel.

Bytes and packets are charged to each drone's radio (its energy). KPIs
(``kpis``): per drone ``<name>.offload.latency_p95_s`` (capture to result)
and ``.latency_p50_s``, ``.frames``; fleet-wide ``offload.latency_p95_s``,
``link.queue_delay_p95_s``, ``ground.queue_delay_mean_s`` /
``ground.queue_delay_p95_s`` and ``ground.utilization`` (busy time / the
fleet's makespan).
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from .. import _check
from ..comm.link import link as _link
from ..compute import device as _device
from ..compute.predict import LatencyFallbackWarning, mac_rule_seconds, predict_latency
from ..compute.runtimes import check_names
from ..control.stages import PILOT
from ..errors import ConfigError
from ..mission.plan import seed_sequence
from ..ml.events import SharedGround


class Offload:
    """Remote inference for ``Fleet(offload=...)``: every ``period_s`` each drone sends
    a frame to the ground station, which runs ``macs`` per frame on ``ground_device``
    and answers (see the module docstring for the channel and queue model)."""

    def __init__(self, *, period_s: float = 1.0, frame_bytes: int = 60_000, result_bytes: int = 200,
                 macs: float = 8.7e9, ground_device: str = "ground-gpu", link="wifi-80211n",
                 shared_link: bool = True, ground_station=(0.0, 0.0, 0.0), model=None,
                 runtime: str | None = None, precision: str | None = None) -> None:
        w = "Offload"
        self.period_s = _check.positive("period_s", period_s, where=w)
        for field, v in (("frame_bytes", frame_bytes), ("result_bytes", result_bytes)):
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise ConfigError(f"{w}: {field} = {v!r} is not allowed; expected an integer >= 1")
        self.frame_bytes, self.result_bytes = frame_bytes, result_bytes
        self.macs = _check.positive("macs", macs, where=w)
        self.ground_device = _device(ground_device)
        self.link = _link(link)
        if not isinstance(shared_link, bool):
            raise ConfigError(f"{w}: shared_link = {shared_link!r} is not allowed; expected "
                              f"True or False")
        self.shared_link = shared_link
        self.ground_station = _check.vector("ground_station", ground_station, 3, where=w)
        self.runtime, self.precision, self.prediction = runtime, precision, None
        if model is not None:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", LatencyFallbackWarning)
                self.prediction = predict_latency(model, self.ground_device, runtime=runtime,
                                                  precision=precision)
            self.macs = self.prediction.macs
            self.compute_s = self.prediction.seconds
        else:
            check_names(runtime, precision, where=w)
            self.compute_s = mac_rule_seconds(self.macs, self.ground_device)

    def to_dict(self) -> dict:
        """JSON-ready description for the fleet's scenario."""
        return {"period_s": self.period_s, "frame_bytes": self.frame_bytes,
                "result_bytes": self.result_bytes, "macs": self.macs,
                "ground_device": self.ground_device.name, "link": self.link.name,
                "shared_link": self.shared_link, "ground_station": list(self.ground_station),
                "compute_s": self.compute_s,
                **({"prediction": self.prediction.to_dict()} if self.prediction else {})}


class OffloadStep:
    """The offload on the fleet's clock (``step(t, members)`` when due)."""

    def __init__(self, spec: Offload, runs):
        self.spec = spec
        self.runs = runs
        self.rngs = [np.random.default_rng(seed_sequence(r.plan.seed, "link")) for r in runs]
        self.next_due = spec.period_s
        self._k = 0
        n = len(runs)
        # the channel(s) and the ground device: the queues the remote tasks use too
        self.ground = SharedGround(spec.shared_link)
        self.latency: list[list[float]] = [[] for _ in range(n)]

    def step(self, t: float, members) -> None:
        """Send this period's frames of the drones flying their plan (``members``:
        the loop's drones, ``mission.loop.Member``)."""
        sp = self.spec
        self._k += 1
        self.next_due = (self._k + 1) * sp.period_s - 1e-9
        n = len(members)
        order = [(self._k + j) % n for j in range(n)]             # round-robin start
        gs = sp.ground_station
        arrivals = []
        for i in order:
            m = members[i]
            s = m.s
            if not m.active or s.stage != PILOT:
                continue
            q = s.q
            dist = math.dist((q[0], q[1], q[2]), gs)
            up = sp.link.transfer(sp.frame_bytes, dist, self.rngs[i], direction="up")
            start = self.ground.uplink(i, t, up.seconds)
            self.runs[i].traffic.add(up.bytes_on_air, up.packets, 0, 0)
            if up.delivered:
                arrivals.append((start + up.seconds, i, dist))
        g = self.ground
        for arrive, i, dist in sorted(arrivals):
            g.compute(arrive, sp.compute_s)
            down = sp.link.transfer(sp.result_bytes, dist, self.rngs[i], direction="down")
            self.runs[i].traffic.add(0, 0, down.bytes_on_air, down.packets)
            self.latency[i].append(g.ground_free + down.seconds - t)

    def kpis(self, names, makespan_s: float) -> dict:
        out = {}
        for name, lat in zip(names, self.latency):
            out[f"{name}.offload.frames"] = float(len(lat))
            out[f"{name}.offload.latency_p50_s"] = _pct(lat, 50)
            out[f"{name}.offload.latency_p95_s"] = _pct(lat, 95)
        every = [x for lat in self.latency for x in lat]
        out["offload.latency_p95_s"] = _pct(every, 95)
        out.update(ground_kpis(self.ground, makespan_s))
        return out


def share_ground(runs, shared_link: bool) -> SharedGround:
    """One ground station for the remote tasks of every drone (``ml.events.SharedGround``)."""
    ground = SharedGround(shared_link)
    for i, r in enumerate(runs):
        for runner in r.scheduler.runners:
            if runner.task.execution == "remote":
                runner.share(ground, i)
    return ground


def ground_kpis(g, makespan_s: float) -> dict:
    """The shared ground station's KPIs from its ``ml.events.SharedGround`` (the
    offload's or the remote tasks')."""
    return {"link.queue_delay_p95_s": _pct(g.link_wait, 95),
            "ground.queue_delay_mean_s": float(np.mean(g.ground_wait)) if g.ground_wait
            else math.nan,
            "ground.queue_delay_p95_s": _pct(g.ground_wait, 95),
            "ground.utilization": min(1.0, g.busy_s / makespan_s) if makespan_s > 0 else 0.0}


def _pct(xs, q) -> float:
    return float(np.percentile(xs, q)) if len(xs) else math.nan
