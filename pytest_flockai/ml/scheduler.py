"""The task scheduler: ML tasks (and the dataset recorder) fed on the simulated clock.

A clocked component. When a task or the recorder wants a frame and the drone
is surveying (pilot and return stages; not on the ground), it reads the
sensor once (a camera renders only then), gives the frame and its ground
truth to every consumer that is due, and notes the drone's position. Between
frames, one comparison per tick. The energy integrator takes the SoC busy
time and the task traffic from ``take_usage``; the result builder takes the
KPIs, events and truth records.
"""

from __future__ import annotations

import math

import numpy as np

from ..clock import CLOCK_EPS, Clocked
from ..control.stages import PILOT, RETURN
from .analysis import coco_pair
from .gallery import worst_frames
from .metrics import percentile
from .oracle import OracleFrame, needs_pixels
from .task_energy import task_energy_kpis
from .task_runner import DeviceClock, TaskRunner

#: frames a detection task's gallery shows
GALLERY_FRAMES = 6
#: MB: estimate of Raspberry Pi OS Lite + flight software resident set
OS_MEMORY_MB = 250.0


def memory_utilization(tasks, device) -> float:
    """Share of the on-board computer's memory in use: the OS plus the weights
    (4 bytes per parameter) of the on-board models."""
    if device is None:
        return 0.0
    mem = OS_MEMORY_MB + sum(4e-6 * float(getattr(tk.model, "params", 0) or 0) for tk in tasks
                             if tk.execution == "onboard")
    return min(1.0, mem / device.memory_mb)


class DatasetRecorder:
    """Takes camera frames and their truth every ``period_s`` for ``export_dataset``."""

    sensor = "camera"

    def __init__(self, period_s: float):
        self.period_s = period_s
        self.next_frame_t = 0.0
        self.records: list = []

    def due(self, t: float) -> bool:
        return t >= self.next_frame_t - CLOCK_EPS

    def skip(self, t: float) -> None:
        self.on_frame(t, None, None, None)

    def on_frame(self, t, frame, truth, pos):
        if frame is not None:
            self.records.append((t, frame, truth))
        while self.next_frame_t <= t + CLOCK_EPS:
            self.next_frame_t += self.period_s


class TaskScheduler(Clocked):
    """``tasks``: the mission's Tasks; ``seeds``: one SeedSequence per task."""

    def __init__(self, state, tasks, seeds, suite, data, *, recorder: DatasetRecorder | None = None,
                 computer=None):
        self.st, self.suite, self.data = state, suite, data
        onboard_clock = DeviceClock()        # one on-board computer, shared by its tasks
        self.device_clock = onboard_clock
        self.runners: list[TaskRunner] = []
        #: oracle models' random stream (their own, spawned beside the tasks' streams)
        self.oracle_rng = (np.random.default_rng(np.random.SeedSequence(
            seeds[0].entropy, spawn_key=tuple(seeds[0].spawn_key) + (99,))) if seeds else None)
        for tk, seed in zip(tasks, seeds):
            r = TaskRunner(tk)
            r.bind(np.random.default_rng(seed), t0=0.0, device_clock=onboard_clock,
                   device=computer if tk.device is None else None)   # None: the drone's own
            self.runners.append(r)
        self.recorder = recorder
        #: the task runners and the dataset recorder: each has due(t), next_frame_t, a sensor
        self.consumers: list = self.runners + ([recorder] if recorder is not None else [])
        self.next_due = min((c.next_frame_t for c in self.consumers), default=math.inf) - CLOCK_EPS
        self.cpu_time_s = 0.0
        self.in_view: list = []          # (t, people in view, blur px) at every frame read
        self.capture_pos: dict = {}      # t -> drone (x, y, z) at captures
        #: t -> what the drone knew of its pose at captures: (x, y, z, qw, qx, qy, qz), the
        #: navigation estimate when flying on estimates (policies project boxes with it)
        self.capture_nav: dict = {}
        #: per task: [busy s, tx bytes, tx packets, rx bytes, rx packets] charged to the energy
        self.charged = [[0.0, 0, 0, 0, 0] for _ in self.runners]

    def step(self, t: float) -> None:
        stage = self.st.stage
        if stage != PILOT and stage != RETURN:
            return
        q = self.st.q
        pos = (q[0], q[1], q[2])
        due = [c for c in self.consumers if c.due(t)]
        cache = {}
        for c in due:
            name = getattr(c, "sensor", None) or c.task.sensor
            if name not in cache:
                pixels = any(needs_pixels(getattr(getattr(o, "task", None), "model", None))
                             for o in due if (getattr(o, "sensor", None) or o.task.sensor) == name)
                cache[name] = self._read(name, t, pixels)
                self.capture_pos[round(t, 6)] = pos
                self.capture_nav[round(t, 6)] = tuple(self.st.qc[:7])
            value, truth = cache[name]
            if not needs_pixels(getattr(getattr(c, "task", None), "model", None)):
                value = self._oracle_frame(name, truth)
            if value is None and getattr(self.suite[name], "ended", False):
                c.skip(t)           # a replay without loop is over: no frame, no inference
                continue
            c.on_frame(t, value, truth, pos)
        self.next_due = min((c.next_frame_t for c in self.consumers), default=math.inf) - CLOCK_EPS

    def refresh(self) -> None:
        """Recompute when the next frame is due (after a task's period changed)."""
        self.next_due = min((c.next_frame_t for c in self.consumers), default=math.inf) - CLOCK_EPS

    def retask(self, runner: TaskRunner, t: float, **changes) -> None:
        """Change a running task from time t on (a policy's action): ``period_s``,
        ``model``, ``execution`` (``Task.replace``: a checked copy, the mission's Task is
        untouched), or
        ``enabled`` (False: no frame until enabled again; True: a frame now)."""
        enabled = changes.pop("enabled", None)
        if changes:
            last = runner.next_frame_t - runner.task.period_s
            runner.task = runner.task.replace(**changes)     # a checked copy
            if "period_s" in changes and runner.next_frame_t != math.inf:
                runner._t0 = last
                runner._next_frame_t = max(t, last + runner.task.period_s)
            if "execution" in changes:
                runner._shared = self.device_clock if runner.task.execution == "onboard" else None
        if enabled is False:
            runner._next_frame_t = math.inf
        elif enabled is True and runner.next_frame_t == math.inf:
            runner._t0 = runner._next_frame_t = t
        self.refresh()

    def _read(self, name, t, pixels=True):
        if name not in self.suite:
            return None, None
        sensor = self.suite[name]
        if not pixels and hasattr(sensor, "truth"):      # oracles only: no render
            value, truth = None, sensor.truth(t, self.data)
        else:
            value = self.suite.read(name, t, self.data)
            truth = getattr(sensor, "last_truth", None)
        if truth is not None:
            du, dv = getattr(truth, "blur_px", (0.0, 0.0))
            self.in_view.append((t, truth.count, math.hypot(du, dv)))
        return value, truth

    def _oracle_frame(self, name, truth) -> OracleFrame:
        cam = self.suite[name] if name in self.suite else None
        shape = (getattr(cam, "height", 0), getattr(cam, "width", 0), 3)
        return OracleFrame(truth, shape, self.oracle_rng)

    def take_usage(self, t: float):
        """(SoC busy s, tx bytes, tx packets, rx bytes, rx packets) of all tasks
        since the last call, after advancing each task to t."""
        busy = 0.0
        tb = tp = rb = rp = 0
        for r, ch in zip(self.runners, self.charged):
            r.advance(t)
            b, a1, a2, a3, a4, raw = r.take_usage()
            if b or a1 or a3:
                ch[0] += b
                ch[1] += a1
                ch[2] += a2
                ch[3] += a3
                ch[4] += a4
            busy += b
            tb += a1
            tp += a2
            rb += a3
            rp += a4
            self.cpu_time_s += raw          # busy time, not weighted by the power share
        return busy, tb, tp, rb, rp

    def kpis(self) -> tuple[dict, dict]:
        """(combined KPIs over all tasks, each task's own KPIs by task name)."""
        by = {r.task.name: r.kpis() for r in self.runners}
        if len(self.runners) == 1:
            return next(iter(by.values())), by
        lat = [e.latency_s for r in self.runners for e in r.events if e.ok]
        comb = {"inference_count": float(len(lat)),
                "inference_latency_p50_s": percentile(lat, 50),
                "inference_latency_p95_s": percentile(lat, 95),
                "inference_latency_max_s": max(lat) if lat else math.nan,
                "frames_dropped": sum(k["frames_dropped"] for k in by.values()),
                "inference_failures": sum(k["inference_failures"] for k in by.values())}
        return comb, by

    def energy_kpis(self, meter) -> dict:
        """``<task>.energy_j`` and its parts, and ``energy_untasked_j`` (``task_energy``)."""
        if not self.runners:
            return {}
        return task_energy_kpis([r.task.name for r in self.runners], self.charged, meter)

    def coco_pairs(self) -> dict:
        """{task: (COCO ground truth, COCO results)} of the detection tasks (``analysis``)."""
        return {r.task.name: coco_pair(r.scorer.records.values(), r.task.classes,
                                       min_visible=r.task.min_visible)
                for r in self.runners if r.task.evaluate == "detection" and r.scorer.records}

    def galleries(self, n: int = GALLERY_FRAMES) -> dict:
        """{task: its worst frames drawn (``gallery.worst_frames``)} of the detection tasks."""
        return {r.task.name: worst_frames(r.scorer.records.values(), r.task, n)
                for r in self.runners if r.task.evaluate == "detection" and r.scorer.records}

    def evaluation_kpis(self) -> dict:
        """The accuracy KPIs of the detection, classification and custom tasks, as
        ``<task>.<kpi>`` and, with a single task, also unprefixed."""
        out = {}
        for r in self.runners:
            ev = r.evaluation()
            out.update({f"{r.task.name}.{k}": v for k, v in ev.items()})
            if len(self.runners) == 1:
                out.update(ev)
        return out

    def inference_events(self) -> list[dict]:
        """Every inference as an event dict, with the drone's position and the frame's
        motion blur length (``blur_px``) at capture."""
        self._blur = {round(t, 6): b for t, _, b in self.in_view}
        out = []
        for r in self.runners:
            thr = r.task.crowd_threshold
            for e in r.events:
                d = e.to_dict()
                d["t"] = round(float(e.t_done if e.t_done is not None else e.t_capture), 6)
                pos = self.capture_pos.get(round(float(e.t_capture), 6))
                if pos is not None:
                    d["x"], d["y"], d["z"] = pos
                blur = self._blur.get(round(float(e.t_capture), 6))
                if blur is not None:
                    d["blur_px"] = blur
                d["detected"] = bool(e.ok and e.count is not None and e.count >= thr)
                out.append(d)
        return out
