"""The task runner: one ML task (``ml.task.Task``) executed during a mission, on simulated seconds:
``bind(rng)`` before a flight; ``on_frame(t, frame, truth, drone_pos)`` when ``due(t)``;
``advance(t)`` every tick; ``take_usage()`` per energy tick; ``kpis()`` at the end.

What happens on a frame (``on_frame``): if the previous inference is still running, the frame is
dropped (``on_busy="drop"``, counted in ``frames_dropped``) or queued (``on_busy="queue"``, up to
``max_queue`` waiting frames, then dropped). Otherwise the runner RUNS the real model on the frame
now (the prediction is real) and schedules its simulated timeline:

- ``onboard``: compute on the drone's device for the modeled latency ``overhead_s + MACs /
  macs_per_s`` (or the measured, scaled host time). The result is on board at the end: that is the
  inference latency. Then, as in the paper's scenario 1 (section 5.2), the drone sends the frame,
  annotated with the count and position and JPEG-encoded with OpenCV (real size), when the
  predicted count reaches ``crowd_threshold`` (``alert="frame"``); otherwise a ``result_bytes``
  result message (count, position, time). ``alert="result"`` always sends the small message.
- ``remote`` (the paper's scenario 2): the drone JPEG-encodes the frame (``cv2.imencode``,
  ``jpeg_quality``: real byte size), sends it up the link at the current distance to the
  ``ground_station``, the ground decodes it and runs the model on the *decoded* frame (JPEG
  artefacts reach the model) for the modeled latency on ``ground_device``, then sends
  ``result_bytes`` back. Latency = capture to result back on the drone. One request in flight at a
  time (a synchronous client, as the paper's). In a fleet (``share``) the uplink waits for the
  shared channel, the inference for the shared ground device. The model always runs in flight.

SoC busy time charged to the drone: the inference (onboard), JPEG encoding of frames and alerts
(``JPEG_MACS_PER_PIXEL`` per pixel), ``update_macs`` of models learning in flight. A model
raising (or a link out of range) fails that inference (``ok=False``, ``inference_failures``)."""

from __future__ import annotations

import bisect
import math
import time

import numpy as np

from .. import memo
from ..comm.link import link as _link
from ..compute.latency import calibrate, compute_seconds, host_scale, resolve_device
from ..errors import ConfigError
from .events import DeviceClock, InferenceEvent
from .jpeg import JPEG_MACS_PER_PIXEL, annotate, decode_jpeg, encode_jpeg, is_image
from .latency_model import InferenceTimer, is_measured
from .metrics import SortedValues, invalid_prediction
from .task import Task
from .task_scoring import Scorer
from .templates import Template

_ZERO_USAGE = (0.0, 0, 0, 0, 0, 0.0)
_NO_EVENTS: tuple = ()
#: the computer of a TaskRunner bound outside a Mission (FlockAI's drone carries a Pi 4)
STANDALONE_DEVICE = "raspberry-pi-4"

class TaskRunner:
    """Runs one ``Task`` on the simulated clock (see the module docstring)."""

    def __init__(self, task: Task):
        if not isinstance(task, Task):
            raise ConfigError(f"TaskRunner: task = {task!r} is not a Task")
        self.task = task
        self._bound = False

    # -- set-up ----------------------------------------------------------------
    def bind(self, rng, *, device=None, ground_device=None, link=None, t0: float = 0.0,
             calibration=None, device_clock: DeviceClock | None = None) -> TaskRunner:
        """Reset for a flight. ``rng``: a numpy Generator (or seed) spawned from the mission seed,
        used for the link's loss and jitter. ``device`` / ``ground_device`` / ``link`` override
        the task's (e.g. the drone's own computer from its blueprint). ``t0``: the flight's start
        time. ``device_clock``: a DeviceClock shared by the on-board tasks of one drone."""
        t = self.task
        self.rng = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
        if device is None:          # outside a Mission there is no drone: the paper's Pi 4
            device = t.device if t.device is not None else STANDALONE_DEVICE
        self.device = resolve_device(device, "device")
        self.ground_device = (resolve_device(ground_device, "ground_device")
                              if ground_device is not None else t.ground_device)
        self.link = _link(link) if link is not None else t.link
        d = self.device if t.execution == "onboard" else self.ground_device
        self.timers = {id(d): InferenceTimer(t, d, self.rng.spawn(1)[0] if is_measured(d) else None)}
        self.calibration = None
        if t.latency == "measured":
            self.calibration = calibration or calibrate()
        self._t0 = float(t0)
        self._next_frame_t = self._t0
        self._clock = self._t0
        self._usage_t = self._t0
        self._free_at = -math.inf
        self._shared = device_clock if t.execution == "onboard" else None
        self._starts: list[float] = []         # start times of scheduled jobs (queue mode)
        self._pending: list = []                # [(t_done, seq, event)] sorted
        self._next_done = math.inf
        self._seq = 0
        self._busy: list = []                   # [(a, b)] SoC busy segments not yet taken
        self._radio: list = []                  # [(t, tx_b, tx_p, rx_b, rx_p)] not yet taken
        self._busy_taken = 0.0
        self.frames = 0
        self.frames_dropped = 0
        self.inference_failures = 0
        self.events: list[InferenceEvent] = []
        self.latencies = SortedValues()         # the ok inferences', sorted as they finish
        self.scorer = Scorer(t)
        self._wall: list[float] = []            # measured mode: host seconds per inference
        self.tx_bytes_total = self.rx_bytes_total = 0
        self.tx_packets_total = self.rx_packets_total = 0
        self.retransmissions = 0
        self._ground, self._who = None, 0       # a fleet's SharedGround (remote tasks)
        self._bound = True
        return self

    def share(self, ground, who: int) -> None:
        """Queue this (remote) task on a fleet's ``SharedGround`` as drone ``who``."""
        self._ground, self._who = ground, who

    def _need_bind(self):
        if not self._bound:
            raise ConfigError(f"task {self.task.name!r}: call runner.bind(rng) before the flight")

    # -- the loop interface ------------------------------------------------------
    @property
    def next_frame_t(self) -> float:
        """When the task next wants a frame (sample grid t0 + k * period_s)."""
        return self._next_frame_t

    def due(self, t: float) -> bool:
        """Whether the task takes a frame at simulated time ``t``."""
        return t >= self._next_frame_t - 1e-9

    def skip(self, t: float) -> None:
        """No frame at t (a replay is over): wait for the next sample time, no inference."""
        k = math.floor((t - self._t0) / self.task.period_s + 1e-9)
        self._next_frame_t = max(self._next_frame_t, self._t0 + (k + 1) * self.task.period_s)

    def on_frame(self, t: float, frame, truth=None, drone_pos=(0.0, 0.0, 0.0)) -> None:
        """A frame from the task's sensor at t; frames before ``next_frame_t`` are ignored."""
        self._need_bind()
        task = self.task
        if t < self._next_frame_t - 1e-9:
            return
        k = math.floor((t - self._t0) / task.period_s + 1e-9)
        self._next_frame_t = self._t0 + (k + 1) * task.period_s
        idx = self.frames
        self.frames += 1
        tc = self.scorer.frame(idx, frame, truth, drone_pos, t)
        if self._free_at > t + 1e-12:      # this task's model is still busy
            if task.on_busy == "drop":
                self.frames_dropped += 1
                return
            starts = self._starts
            while starts and starts[0] <= t:
                starts.pop(0)
            if len(starts) >= task.max_queue:
                self.frames_dropped += 1
                return
        start = max(t, self._free_at)
        if self._shared is not None:       # wait for another task on the same computer
            start = max(start, self._shared.free_at)
        if task.on_busy == "queue":
            self._starts.append(start)
        pos = np.asarray(drone_pos, dtype=np.float64)
        dist = float(np.linalg.norm(pos - np.asarray(task.ground_station)))
        if task.execution == "onboard":
            ev, free_at = self._onboard(idx, t, start, frame, tc, pos)
        else:
            ev, free_at = self._remote(idx, t, start, frame, tc, dist)
        self._free_at = free_at
        if self._shared is not None:
            self._shared.free_at = max(self._shared.free_at, free_at)
        self._schedule(ev)

    def advance(self, t: float):
        """Inferences whose result is available by time t (in finish order)."""
        self._clock = t
        if t < self._next_done:
            return _NO_EVENTS
        out = []
        pend = self._pending
        while pend and pend[0][0] <= t:
            ev = pend.pop(0)[2]
            out.append(ev)
            self.events.append(ev)
            self.inference_failures += not ev.ok
            if ev.ok:
                self.latencies.add(ev.latency_s)
            self.scorer.finished(ev)
        self._next_done = pend[0][0] if pend else math.inf
        return out

    def take_usage(self):
        """(SoC busy s weighted by the share of its busy power drawn, tx/rx bytes and
        packets, SoC busy s) since the previous call (``InferenceTimer.power_share``)."""
        a, b = self._usage_t, self._clock
        self._usage_t = b
        if not self._busy and not self._radio:
            return _ZERO_USAGE
        busy = raw = 0.0
        if self._busy:
            keep = []
            for s, e, w in self._busy:
                lo, hi = max(s, a), min(e, b)
                if hi > lo:
                    raw += hi - lo
                    busy += (hi - lo) * w
                if e > b:
                    keep.append((s, e, w))
            self._busy = keep
            self._busy_taken += raw
        txb = txp = rxb = rxp = 0
        if self._radio:
            keep = []
            for rec in self._radio:
                if rec[0] <= b:
                    txb += rec[1]
                    txp += rec[2]
                    rxb += rec[3]
                    rxp += rec[4]
                else:
                    keep.append(rec)
            self._radio = keep
        return (busy, txb, txp, rxb, rxp, raw)

    # -- timelines ---------------------------------------------------------------
    def _schedule(self, ev: InferenceEvent):
        self._seq += 1
        bisect.insort(self._pending, (ev.t_done, self._seq, ev))
        self._next_done = self._pending[0][0]

    def _busy_seg(self, a: float, dur: float, share: float = 1.0):
        if dur > 0.0:
            self._busy.append((a, a + dur, share))

    def _radio_rec(self, t: float, tr, direction: str):
        if direction == "up":
            self._radio.append((t, tr.payload_bytes, tr.packets, 0, 0))
            self.tx_bytes_total += tr.payload_bytes
            self.tx_packets_total += tr.packets
        else:
            self._radio.append((t, 0, 0, tr.payload_bytes, tr.packets))
            self.rx_bytes_total += tr.payload_bytes
            self.rx_packets_total += tr.packets
        self.retransmissions += tr.retransmissions

    def _infer(self, model, frame, device):
        """Run the real model; (prediction, error, device seconds)."""
        measured = self.task.latency == "measured"
        pred = err = None
        t0 = time.perf_counter()
        try:
            with memo.remembering(None):    # see the module docstring
                pred = model(frame)
        except Exception as e:  # the flight goes on
            err = f"{type(e).__name__}: {e}"
        wall = time.perf_counter() - t0
        if measured:
            self._wall.append(wall)
            sc = host_scale(device, self.calibration)
            return pred, err, sc.overhead_s + wall * sc.factor
        macs = None
        try:
            macs = model.macs_for(frame) if hasattr(model, "macs_for") else model.macs
        except Exception as e:
            err = err or f"MAC count failed: {type(e).__name__}: {e}"
        return pred, err, self.timers[id(device)].seconds(model, frame, macs)

    def _encode(self, frame, device):
        """(payload bytes, bytes count, device seconds) to send a sensor value."""
        if is_image(frame):
            t0 = time.perf_counter()
            data = encode_jpeg(frame, self.task.jpeg_quality)
            wall = time.perf_counter() - t0
            if self.task.latency == "measured":
                secs = wall * host_scale(device, self.calibration).factor
            else:
                secs = compute_seconds(frame.shape[0] * frame.shape[1] * JPEG_MACS_PER_PIXEL, device)
            return data, len(data), secs
        raw = np.asarray(frame, dtype=np.float64).tobytes()
        return raw, len(raw), 0.0

    def _update(self, model, frame, start: float) -> float:
        if isinstance(model, Template) and model.learns_in_flight:
            try:
                model.update(frame)
            except Exception:
                pass
            secs = float(getattr(model, "update_macs", 0) or 0) / self.device.macs_per_s
            self._busy_seg(start, secs)
            return secs
        return 0.0

    def _onboard(self, idx, t, start, frame, tc, pos):
        task, dev = self.task, self.device
        pred, err, compute = self._infer(task.model, frame, dev)
        self._busy_seg(start, compute, self.timers[id(dev)].power_share)
        done = start + compute
        free = done + self._update(task.model, frame, done)
        count = self.scorer.count(pred, idx, frame) if err is None else None
        err = err or invalid_prediction(pred, count, task, self.scorer.parse_error)
        tx, alert = 0, False
        if err is None:
            d = float(np.linalg.norm(pos - np.asarray(task.ground_station)))
            if (task.alert == "frame" and count is not None and count >= task.crowd_threshold
                    and is_image(frame)):
                data, n, enc = self._encode(annotate(frame, count, pos), dev)
                self._busy_seg(free, enc)
                free += enc
                alert = True
            else:
                n = task.result_bytes
            tr = self.link.transfer(n, d, self.rng, direction="up")
            self._radio_rec(free, tr, "up")
            tx = tr.payload_bytes
        done += float(getattr(task.model, "delay_s", 0.0) or 0.0)   # an oracle's delay
        ev = InferenceEvent(task=task.name, frame_index=idx, t_capture=t, t_start=start, t_done=done,
                            latency_s=done - t, compute_s=compute, prediction=pred, count=count,
                            truth_count=tc, ok=err is None, error=err, tx_bytes=tx, rx_bytes=0,
                            execution="onboard", alert_sent=alert)
        return ev, free

    def _remote(self, idx, t, start, frame, tc, dist):
        task, dev = self.task, self.device
        data, n, enc = self._encode(frame, dev)
        self._busy_seg(start, enc)
        t_up = start + enc
        up = self.link.transfer(n, dist, self.rng, direction="up")
        g = self._ground
        if g is not None:                  # a fleet: wait for the shared channel
            t_up = g.uplink(self._who, t_up, up.seconds)
        self._radio_rec(t_up, up, "up")
        pred = err = count = None
        compute = 0.0
        rx = 0
        if not up.delivered:
            err = (f"link {self.link.name!r} down at {dist:.0f} m "
                   f"(range {self.link.range_m():.0f} m)")
            done = t_up + up.seconds
        else:
            frame_g = decode_jpeg(data, grey=np.asarray(frame).ndim == 2) if is_image(frame) else frame
            pred, err, compute = self._infer(task.model, frame_g, self.ground_device)
            t_g = t_up + up.seconds
            t_g = (g.compute(t_g, compute) if g is not None else t_g) + compute
            down = self.link.transfer(task.result_bytes, dist, self.rng, direction="down")
            self._radio_rec(t_g, down, "down")
            rx = down.payload_bytes
            done = t_g + down.seconds
            if not down.delivered and err is None:
                err = f"link {self.link.name!r} down at {dist:.0f} m on the downlink"
            if err is None:
                count = self.scorer.count(pred, idx, frame_g)
                err = invalid_prediction(pred, count, task, self.scorer.parse_error)
        ev = InferenceEvent(task=task.name, frame_index=idx, t_capture=t, t_start=start, t_done=done,
                            latency_s=done - t, compute_s=compute, prediction=pred, count=count,
                            truth_count=tc, ok=err is None, error=err, tx_bytes=up.payload_bytes,
                            rx_bytes=rx, execution="remote", alert_sent=False)
        return ev, done

    # -- results -------------------------------------------------------------------
    def cpu_time_s(self) -> float:
        """Drone SoC busy seconds up to the last ``advance(t)``."""
        b = self._clock
        pend = sum(max(0.0, min(e, b) - max(s, self._usage_t)) for s, e, _ in self._busy)
        return self._busy_taken + pend

    def kpis(self) -> dict:
        """The task's KPIs (unprefixed names; the mission prefixes per task)."""
        self._need_bind()
        lat = self.latencies
        out = {
            "inference_count": float(len(lat)),
            "inference_latency_p50_s": lat.percentile(50),
            "inference_latency_p95_s": lat.percentile(95),
            "inference_latency_max_s": lat.max(),
            "frames_dropped": float(self.frames_dropped),
            "inference_failures": float(self.inference_failures),
            "cpu_time_s": self.cpu_time_s(),
        }
        return {**out, **self.scorer.count_kpis()}

    def evaluation(self) -> dict:
        """The end-of-flight accuracy KPIs (``Scorer.evaluation``)."""
        return self.scorer.evaluation()

    def summary(self) -> dict:
        """More than the KPIs: frames, traffic, crowd encounters, measured-mode spread."""
        out = {"task": self.task.name, "frames": self.frames,
               "frames_dropped": self.frames_dropped, "inference_failures": self.inference_failures,
               "tx_bytes": self.tx_bytes_total, "tx_packets": self.tx_packets_total,
               "rx_bytes": self.rx_bytes_total, "rx_packets": self.rx_packets_total,
               "retransmissions": self.retransmissions, "in_flight": len(self._pending)}
        m = self.scorer.crowd()
        if m is not None:
            out.update(crowd_encounters=m["crowd_encounters"], crowds_missed=m["crowds_missed"])
        if self._wall and self.calibration is not None:     # measured latency: calibrated
            w = np.asarray(self._wall)
            p10, p50, p90 = (float(x) for x in np.percentile(w, (10, 50, 90)))
            out["measured_wall_s"] = {"median": p50, "p10": p10, "p90": p90, "n": int(w.size)}
            dev = self.device if self.task.execution == "onboard" else self.ground_device
            out["calibration"] = {**self.calibration.to_dict(),
                                  "scale": host_scale(dev, self.calibration).to_dict()}
        return out


__all__ = ["DeviceClock", "InferenceEvent", "TaskRunner"]
