"""What a task runner hands out: inference events, and the clock of a shared
on-board computer."""

from __future__ import annotations

import math


class DeviceClock:
    """When a shared on-board computer is next free: the on-board tasks of one
    drone share one, so one task's inference waits for another's to finish
    (a frame is dropped only while its own task's model is still busy)."""

    __slots__ = ("free_at",)

    def __init__(self):
        self.free_at = -math.inf


class InferenceEvent:
    """One inference, as returned by ``TaskRunner.advance``."""

    __slots__ = ("task", "frame_index", "t_capture", "t_start", "t_done", "latency_s",
                 "compute_s", "prediction", "count", "truth_count", "ok", "error",
                 "tx_bytes", "rx_bytes", "execution", "alert_sent")

    def __init__(self, **kw):
        for k in self.__slots__:
            setattr(self, k, kw.get(k))

    def to_dict(self) -> dict:
        d = {k: getattr(self, k) for k in self.__slots__ if k != "prediction"}
        d["kind"] = "inference"
        return d

    def __repr__(self):
        state = "ok" if self.ok else f"failed: {self.error}"
        return (f"InferenceEvent({self.task!r}, frame={self.frame_index}, t={self.t_capture:.3f}, "
                f"latency={self.latency_s:.4f} s, count={self.count}, {state})")
