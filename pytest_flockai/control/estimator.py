"""A small navigation estimator for flying on noisy sensors (``fly_on="estimate"``).

Position and velocity come from GPS (white noise, 10 Hz) and altitude from the
barometer, blended by a complementary filter: between fixes the position is
predicted with the estimated velocity; each GPS fix pulls the position towards
it with time constant ``tau_pos_s`` and sets the velocity (GPS Doppler velocity
is far less noisy than position); each barometer reading pulls the altitude
with ``tau_alt_s``. Attitude and body rates stay the true ones: an AHRS is
assumed good enough (its errors are not modelled).
"""

from __future__ import annotations


class NavEstimator:
    def __init__(self, *, tau_pos_s: float = 2.0, tau_alt_s: float = 0.5):
        self.tau_pos_s = tau_pos_s
        self.tau_alt_s = tau_alt_s
        self.p = None
        self.v = [0.0, 0.0, 0.0]
        self._gps_n = self._baro_n = 0
        self._t = None

    def update(self, t, q, v, suite):
        """Return (q_est, v_est): q/v lists with position and velocity replaced by estimates."""
        if self.p is None:                       # initialised on the ground at the true home
            self.p = [q[0], q[1], q[2]]
            self._t = t
        dt = t - self._t
        self._t = t
        p, ve = self.p, self.v
        p[0] += ve[0] * dt
        p[1] += ve[1] * dt
        p[2] += ve[2] * dt
        counts = suite.counts
        if "gps" in counts and counts["gps"] != self._gps_n:
            self._gps_n = counts["gps"]
            g = suite.latest["gps"]
            k = min(1.0, (1.0 / suite["gps"].rate_hz) / self.tau_pos_s)
            p[0] += k * (g[0] - p[0])
            p[1] += k * (g[1] - p[1])
            ve[0], ve[1], ve[2] = float(g[3]), float(g[4]), float(g[5])
            if "barometer" not in counts:
                p[2] += k * (g[2] - p[2])
        if "barometer" in counts and counts["barometer"] != self._baro_n:
            self._baro_n = counts["barometer"]
            k = min(1.0, (1.0 / suite["barometer"].rate_hz) / self.tau_alt_s)
            p[2] += k * (suite.latest["barometer"] - p[2])
        return [p[0], p[1], p[2], q[3], q[4], q[5], q[6]], [ve[0], ve[1], ve[2], v[3], v[4], v[5]]
