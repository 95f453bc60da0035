"""What a task runner hands out: inference events, and the clock of a shared
on-board computer."""

from __future__ import annotations

import math
from typing import Any


class DeviceClock:
    """When a shared on-board computer is next free: the on-board tasks of one
    drone share one, so one task's inference waits for another's to finish
    (a frame is dropped only while its own task's model is still busy)."""

    __slots__ = ("free_at",)

    def __init__(self):
        self.free_at = -math.inf


class SharedGround:
    """One ground station serving the remote tasks of several drones (a fleet): a
    radio channel that carries one uplink at a time (``shared_link=True``; else a
    channel per drone) and one ground device that runs one inference at a time,
    each a FIFO server in the order requests reach it, as ``fleet.Offload``
    models the fleet's frames. Requests of one instant are served in the order
    they are made (the fleet steps its drones in order). It keeps the waits and
    the device's busy time for the fleet's KPIs."""

    def __init__(self, shared_link: bool = True):
        self.shared_link = shared_link
        self.channel_free: dict = {}
        self.ground_free = -math.inf
        self.busy_s = 0.0
        self.link_wait: list = []
        self.ground_wait: list = []

    def uplink(self, who: int, t: float, seconds: float) -> float:
        """Start of an uplink of ``seconds`` ready at ``t`` from drone ``who``."""
        key = 0 if self.shared_link else who
        start = max(t, self.channel_free.get(key, -math.inf))
        self.channel_free[key] = start + seconds
        self.link_wait.append(start - t)
        return start

    def compute(self, t: float, seconds: float) -> float:
        """Start of an inference of ``seconds`` arriving at ``t``."""
        start = max(t, self.ground_free)
        self.ground_free = start + seconds
        self.busy_s += seconds
        self.ground_wait.append(start - t)
        return start


class InferenceEvent:
    """One inference, as returned by ``TaskRunner.advance``."""

    __slots__ = ("task", "frame_index", "t_capture", "t_start", "t_done", "latency_s",
                 "compute_s", "prediction", "count", "truth_count", "ok", "error",
                 "tx_bytes", "rx_bytes", "execution", "alert_sent")
    # every slot is set by __init__, None when not given (the dataset evaluation gives
    # no times; the flight loop gives them all)
    task: str
    frame_index: int
    t_capture: float
    t_start: float | None
    t_done: float
    latency_s: float
    compute_s: float | None
    prediction: Any
    count: float | None
    truth_count: float | None
    ok: bool
    error: str | None
    tx_bytes: int | None
    rx_bytes: int | None
    execution: str | None
    alert_sent: bool | None

    def __init__(self, **kw: Any) -> None:
        for k in self.__slots__:
            setattr(self, k, kw.get(k))

    def to_dict(self) -> dict:
        """The fields as a JSON-ready dict."""
        d = {k: getattr(self, k) for k in self.__slots__ if k != "prediction"}
        d["kind"] = "inference"
        return d

    def __repr__(self):
        state = "ok" if self.ok else f"failed: {self.error}"
        return (f"InferenceEvent({self.task!r}, frame={self.frame_index}, t={self.t_capture:.3f}, "
                f"latency={self.latency_s:.4f} s, count={self.count}, {state})")
