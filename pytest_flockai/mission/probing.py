"""The probes as a clocked component: fill the ``RunView`` from the flight's
components and let the probe hub sample the probes that are due."""

from __future__ import annotations

from ..clock import CLOCK_EPS, Clocked
from ..control.stages import STAGES


class ProbeStep(Clocked):
    def __init__(self, hub, view, state, book, traffic, suite, tasks, mem_utilization: float):
        self.hub, self.view, self.st = hub, view, state
        self.book, self.traffic, self.suite, self.tasks = book, traffic, suite, tasks
        self.mem_utilization = mem_utilization
        self.next_due = hub.next_due - CLOCK_EPS

    def step(self, t: float) -> None:
        self.sync(t, self.st.q, self.st.v, self.st.stage)
        self.hub.sample(t, self.view)
        self.next_due = self.hub.next_due - CLOCK_EPS

    def sync(self, t, q, v, stage) -> None:
        vw, book, tr = self.view, self.book, self.traffic
        vw.t = t
        vw.position = (q[0], q[1], q[2])
        vw.velocity = (v[0], v[1], v[2])
        vw.stage = STAGES[stage]
        vw.phase_time = book.phase_time
        vw.distance_m, vw.max_speed_mps = book.distance_m, book.max_speed_mps
        vw.tracking_error_max_m = book.tracking_error_max_m
        vw.crashed = self.st.crashed
        vw.bytes_in, vw.bytes_out = tr.bytes_in, tr.bytes_out
        vw.packets_in, vw.packets_out = tr.packets_in, tr.packets_out
        vw.cpu_time_s = self.tasks.cpu_time_s if self.tasks is not None else 0.0
        vw.mem_utilization = self.mem_utilization
        vw.sensors = self.suite.latest
        if self.tasks is not None:
            vw.task_kpis, vw.task_kpis_by_task = self.tasks.kpis()

    def final(self, t, q, v, stage) -> dict:
        """Every KPI: the final sample of each enabled probe."""
        self.sync(t, q, v, stage)
        self.hub.sample(t, self.view, force=True)
        return self.hub.kpis()
