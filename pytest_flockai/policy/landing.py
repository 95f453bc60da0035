"""Precision landing on a fiducial marker, from the marker detector's boxes.

``MarkerLanding(task)`` flies the mission's plan (``search``) until the task (a
``ml.MarkerDetector`` on the camera) delivers a marker; each detection becomes a
ground point through the camera model and the pose the drone believed it had at
capture, and the estimate is the mean of the last ``average`` of them. The drone
flies above the estimate (``approach``), descends to ``descend_to`` metres above
it once it is within ``settle_m`` and slower than 0.3 m/s (``descend``), follows
the estimate as fresh detections refine it, and lands straight down from there
once settled again (``land``). ``landing_error_m``: horizontal distance from where
it touched down to the marker's centre (truth, after the flight).
"""

from __future__ import annotations

import math

from .. import _check
from ..control.tracking import ground_point
from ..errors import ConfigError
from ..world.aruco import TOP_Z
from .base import Policy
from .follow import _task_of

#: m/s: slower than this (estimated ground speed) counts as settled
SETTLED_MPS = 0.3


class MarkerLanding(Policy):
    """Land on a marker found by a detection task (module docstring)."""

    modes = ("search", "approach", "descend", "land")

    def __init__(self, task: str, *, descend_to: float = 3.0, settle_m: float = 0.25,
                 speed: float = 3.0, average: int = 3, marker: str | None = None,
                 name: str = "landing", period_s: float = 0.1):
        super().__init__(name, period_s)
        where = f"policy {self.name!r}"
        if not isinstance(task, str) or not task:
            raise ConfigError(f"{where}: task = {task!r} is not a task name")
        self.task = task
        self.descend_to = _check.positive("descend_to", descend_to, where=where)
        self.settle_m = _check.positive("settle_m", settle_m, where=where)
        self.speed = _check.positive("speed", speed, where=where)
        if isinstance(average, bool) or not isinstance(average, int) or average < 1:
            raise ConfigError(f"{where}: average = {average!r} is not allowed; expected an int >= 1")
        self.average = average
        self.marker = marker

    def check(self, mission) -> None:
        where = f"policy {self.name!r}"
        _task_of(mission, self.task, where)
        markers = [a for a in getattr(mission, "actors", ()) if a.kind == "marker"]
        if not markers:
            raise ConfigError(f"{where}: the mission has no marker to land on; add "
                              f"fa.actors.Marker(x, y) to Mission(actors=[...])")
        if self.marker is not None and self.marker not in [m.name for m in markers]:
            raise ConfigError(f"{where}: marker = {self.marker!r} is not a marker of the mission; "
                              f"allowed: {', '.join(repr(m.name) for m in markers)}")

    def start(self, run) -> None:
        cam = self.drone.camera
        assert cam is not None, "check() made sure a task reads the camera"
        self._lens = (cam.width, cam.height, cam.fov_deg, cam.pitch_deg)
        self._fixes: list = []               # ground points of the marker, latest last
        self._aim: tuple | None = None       # (x, y, z) the drone was last sent to
        markers = run.actors.markers if run.actors is not None else ()
        self._truth = next((m for m in markers if self.marker in (None, m.name)), None)

    def _estimate(self, drone):
        for r in drone.results(self.task):
            if r.ok and r.detections is not None and len(r.detections) and r.nav is not None:
                x0, y0, x1, y1 = r.detections.boxes[0]
                p = ground_point(0.5 * (x0 + x1), 0.5 * (y0 + y1), r.nav, self._lens,
                                 TOP_Z)
                if p is not None:
                    self._fixes.append(p)
        if not self._fixes:
            return None
        last = self._fixes[-self.average:]
        return (sum(p[0] for p in last) / len(last), sum(p[1] for p in last) / len(last))

    def _send(self, drone, x, y, z, tol) -> bool:
        """Fly above (x, y) at z unless already sent within ``tol``; False when refused."""
        if self._aim is None or math.dist(self._aim, (x, y, z)) > tol:
            if not drone.goto(x, y, z, self.speed):
                return False
            self._aim = (x, y, z)
        return True

    def decide(self, t, drone) -> None:
        est = self._estimate(drone)
        mode = self._mode
        if mode is None:
            drone.mode("search")
        if est is None or mode == "land":
            return
        px, py, pz = drone.position
        vx, vy, _ = drone.velocity
        settled = (math.dist((px, py), est) < self.settle_m
                   and math.hypot(vx, vy) < SETTLED_MPS)
        if mode in (None, "search"):
            if self._send(drone, est[0], est[1], pz, 0.0):
                drone.mode("approach")
        elif mode == "approach":
            assert self._aim is not None, "approach starts after a goto: _aim is set"
            self._send(drone, est[0], est[1], self._aim[2], 0.3)
            if settled:
                self._send(drone, est[0], est[1], self.descend_to, 0.0)
                drone.mode("descend")
        else:                                               # descend
            self._send(drone, est[0], est[1], self.descend_to, 0.1)
            if settled and abs(pz - self.descend_to) < 0.2 and drone.land():
                drone.mode("land")

    def kpis(self, run) -> dict:
        out = super().kpis(run)
        err = math.nan
        if self._truth is not None and run.vehicle.t_land is not None:
            q = run.data.qpos
            err = math.dist((float(q[0]), float(q[1])), self._truth.centre)
        out["landing_error_m"] = err
        return out

    def to_dict(self):
        return {**super().to_dict(), "task": self.task, "descend_to": self.descend_to,
                "settle_m": self.settle_m, "speed": self.speed, "average": self.average}


__all__ = ["MarkerLanding"]
