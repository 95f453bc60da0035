"""Perception-driven flight: image boxes to ground points, a target tracker, and
the pilots a policy switches to (follow a track, go to a point and hold, resume
an interrupted plan).

``ground_point`` casts the ray through a pixel from the camera pose the drone
*believed* it had at capture (its navigation estimate and the gimbal's pitch:
``world.truth.gimbal_pose``) onto the horizontal plane at the object's centre
height. ``Tracker`` is a constant-velocity Kalman filter on the ground plane:
measurements arrive late (inference and link latency) and are fused at their
capture time, then the track is predicted to now, so the follower leads a
moving target instead of chasing where it was; between measurements it coasts.
"""

from __future__ import annotations

import math

import numpy as np

from ..world.truth import focal_px, gimbal_pose
from .pilots import Pilot, Waypoints


def yaw_of(quat) -> float:
    """Heading (rad, counter-clockwise from east) of a unit quaternion (w, x, y, z)."""
    w, x, y, z = quat
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def ground_point(u: float, v: float, nav, lens, height: float = 0.0):
    """(x, y) where the ray through pixel (u, v) meets the plane z = ``height``, seen
    from ``nav`` = (x, y, z, qw, qx, qy, qz) with ``lens`` = (width, height, fov_deg,
    pitch_deg); None when the ray does not go down to it."""
    w, h, fov, pitch = lens
    _, R = gimbal_pose((0.0, 0.0, 0.0), yaw_of(nav[3:7]), pitch)
    f = focal_px(fov, h)
    a, b = (u - 0.5 * w) / f, -(v - 0.5 * h) / f
    dx, dy, dz = (float(R[i, 0] * a + R[i, 1] * b - R[i, 2]) for i in range(3))
    if dz >= -1e-6 or nav[2] <= height:
        return None
    s = (height - nav[2]) / dz
    return float(nav[0] + s * dx), float(nav[1] + s * dy)


class Tracker:
    """One target on the ground plane (see the module docstring). ``accel_sd``:
    the target's acceleration noise (m/s^2); ``meas_sd``: the measurement noise (m);
    ``gate_m``: measurements farther than this from the prediction start no update;
    ``confirm``: hits before the track is confirmed."""

    def __init__(self, accel_sd: float = 1.0, meas_sd: float = 1.0, gate_m: float = 15.0,
                 confirm: int = 2):
        self.q, self.r, self.gate_m, self.confirm = accel_sd ** 2, meas_sd ** 2, gate_m, confirm
        self.reset()

    def reset(self) -> None:
        self.x: np.ndarray | None = None      # [x, y, vx, vy]
        self.P: np.ndarray | None = None      # its covariance (set with x)
        self.t = -math.inf            # time of the state (the last measurement's capture)
        self.hits = 0
        self.last_hit = -math.inf     # capture time of the last measurement used
        self.last_delivered = -math.inf   # when that measurement was delivered

    @property
    def confirmed(self) -> bool:
        """A state exists and enough measurements confirmed it."""
        return self.x is not None and self.hits >= self.confirm

    def predict(self, t: float) -> tuple[float, float, float, float]:
        """(x, y, vx, vy) predicted at t; TypeError before the first measurement."""
        x = self.x
        if x is None:
            raise TypeError("Tracker.predict: the track has no state before its first measurement")
        dt = t - self.t
        return x[0] + x[2] * dt, x[1] + x[3] * dt, x[2], x[3]

    def update(self, t: float, px: float, py: float, t_delivered: float | None = None) -> bool:
        """Fuse a measurement captured at t (delivered at ``t_delivered``, default t);
        False when it fails the gate or is older than the state."""
        x0, P0 = self.x, self.P
        if x0 is None or P0 is None:              # both None until the first measurement
            self.x = np.array([px, py, 0.0, 0.0])
            self.P = np.diag([self.r, self.r, 4.0, 4.0])
            self.t, self.hits, self.last_hit = t, 1, t
            self.last_delivered = t if t_delivered is None else t_delivered
            return True
        if t <= self.t:
            return False
        dt = t - self.t
        F = np.array([[1, 0, dt, 0], [0, 1, 0, dt], [0, 0, 1, 0], [0, 0, 0, 1]], float)
        g = np.array([[0.5 * dt * dt, 0], [0, 0.5 * dt * dt], [dt, 0], [0, dt]])
        x = F @ x0
        P = F @ P0 @ F.T + self.q * (g @ g.T)
        y = np.array([px, py]) - x[:2]
        if math.hypot(y[0], y[1]) > self.gate_m:
            return False
        S = P[:2, :2] + self.r * np.eye(2)
        K = P[:, :2] @ np.linalg.inv(S)
        self.x = x + K @ y
        self.P = (np.eye(4) - K[:, :2] @ np.eye(2, 4)) @ P
        self.t, self.last_hit = t, t
        self.last_delivered = t if t_delivered is None else max(t_delivered, self.last_delivered)
        self.hits += 1
        return True


class Track(Pilot):
    """Fly above a ``Tracker``'s target at ``altitude``: a reference point that moves
    toward the predicted target at up to ``speed`` m/s with ``accel`` m/s^2, its
    velocity leading with the target's (never done: the policy decides)."""

    def __init__(self, tracker: Tracker, altitude: float, speed: float = 12.0,
                 accel: float = 3.0, gain: float = 0.6):
        self.tracker, self.altitude = tracker, altitude
        self.speed, self.accel, self.gain = speed, accel, gain
        self.path_length = None

    def start(self, t, position, accel):
        self.t0 = self._t = t
        self._p = [position[0], position[1]]
        self._v = [0.0, 0.0]
        self.accel = min(self.accel, accel)

    def update(self, t, state, sp):
        dt = max(0.0, t - self._t)
        self._t = t
        tx, ty, tvx, tvy = self.tracker.predict(t)
        p, v = self._p, self._v
        wx, wy = tvx + self.gain * (tx - p[0]), tvy + self.gain * (ty - p[1])
        n = math.hypot(wx, wy)
        if n > self.speed:
            wx, wy = wx * self.speed / n, wy * self.speed / n
        dvx, dvy = wx - v[0], wy - v[1]
        dn = math.hypot(dvx, dvy)
        lim = self.accel * dt
        if dn > lim > 0.0:
            dvx, dvy = dvx * lim / dn, dvy * lim / dn
        ax, ay = (dvx / dt, dvy / dt) if dt > 0.0 else (0.0, 0.0)
        v[0] += dvx
        v[1] += dvy
        p[0] += v[0] * dt
        p[1] += v[1] * dt
        sp[0], sp[1], sp[2] = p[0], p[1], self.altitude
        sp[3], sp[4], sp[5] = v[0], v[1], 0.0
        sp[6], sp[7], sp[8] = ax, ay, 0.0
        sp[9] = 0.0
        return False

    def to_dict(self):
        return {"type": "Track", "altitude": self.altitude, "speed": self.speed}


class Goto(Pilot):
    """Fly to ``point`` (x, y, z) at ``speed`` and hold there (never done), heading
    ``yaw`` (rad, counter-clockwise from east; None: 0, as before yaw was given)."""

    def __init__(self, point, speed: float = 5.0, yaw: float | None = None):
        self.inner = Waypoints([point], speed, yaw=0.0 if yaw is None else yaw)
        self.point, self.speed, self.yaw = self.inner.points[0], self.inner.speed, yaw
        self.altitude = self.point[2]

    def start(self, t, position, accel):
        self.t0 = t
        self.inner.start(t, position, accel)

    def update(self, t, state, sp):
        self.inner.update(t, state, sp)
        return False

    def to_dict(self):
        d = {"type": "Goto", "point": list(self.point), "speed": self.speed}
        if self.yaw is not None:
            d["yaw"] = self.yaw
        return d


class Resume(Pilot):
    """Back to an interrupted ``plan``: fly to where its setpoint was when it was
    interrupted (``at``: [x y z ...]), then go on with it from there; its clock is
    shifted by the time spent away."""

    def __init__(self, plan: Pilot, t_paused: float, at, speed: float = 5.0):
        self.plan, self.t_paused, self.speed = plan, t_paused, speed
        self.at = (at[0], at[1], at[2])
        self.altitude = self.at[2]

    def start(self, t, position, accel):
        self.t0 = t
        self._leg = Waypoints([self.at], self.speed)
        self._leg.start(t, position, accel)
        self._back = False

    def update(self, t, state, sp):
        if not self._back:
            if not self._leg.update(t, state, sp):
                return False
            self._back = True
            shift = t - self.t_paused
            self.plan.t0 = getattr(self.plan, "t0", t) + shift
            self.t_paused = t
        return self.plan.update(t, state, sp)

    def to_dict(self):
        return {"type": "Resume", "plan": self.plan.to_dict()}


def plan_left(pilot: Pilot, t: float, sp) -> tuple:
    """(the plan, the time it was left, its setpoint then) for a detour starting at
    ``t`` from ``pilot`` with setpoint ``sp``. A ``Resume`` is unwrapped: back on its
    plan, the plan is left now (its clock was shifted on the way back); still on its way
    back, the plan stays left where and when it was first left."""
    if isinstance(pilot, Resume):
        if getattr(pilot, "_back", False):
            return pilot.plan, t, list(sp)
        return pilot.plan, pilot.t_paused, list(pilot.at)
    return pilot, t, list(sp)


__all__ = ["Goto", "Resume", "Track", "Tracker", "ground_point", "plan_left", "yaw_of"]
