"""CPU cost of the MAVLink front-end (pytest_flockai.app) against the same flight flown
by a Policy. Three flights per round, interleaved, each ``--rounds`` times:

- ``policy``: the waypoints of tests/app/apps/mavsdk_mission.py (3 waypoints, 5 m/s) flown
  by ``Mission(Waypoints, policies=[a Policy doing nothing at the autopilot's 25 Hz])``
  on the drone's estimate, as fast as it computes (no pacing);
- ``paced``: the same flight with that Policy pacing the simulated clock at ``--speed``
  times the wall clock exactly as the autopilot does (the cost of real time alone);
- ``app``: tests/app/apps/mavsdk_mission.py flown by ``fa.app.run(..., speed=--speed)``.

Figures: CPU seconds of THIS process (the simulator and the front-end, all its threads:
``time.process_time``) per simulated second. The app's own process (and what it reaped)
is reported apart (``app CPU``: RUSAGE_CHILDREN). The load average is printed with every
round: the figures are only comparable within one run on one machine. Each round first
flies a policy flight not measured (imports, caches), then the three. The summary gives
the overhead of the app flight over the unpaced and over the paced policy flight
(medians) and PASS or FAIL against the target (``TARGET_PCT``).

The app flight's front-end is also timed on its own (thread CPU in ``Autopilot.decide``,
which holds the commands, the mission, the telemetry, the pacing and the pre-flight wait,
and in the link's thread), printed per round and as a median.

``--against DIR`` runs every round twice, in fresh interpreters, alternating this
checkout and the package in ``DIR`` (e.g. ``git archive`` of an older commit): a
before/after comparison under the same load.

    PYTHONPATH=$PWD python benchmarks/app_overhead.py --speed 20 --rounds 3
    PYTHONPATH=$PWD python benchmarks/app_overhead.py --speed 1 --rounds 1 --against /tmp/old
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
APP = os.path.join(HERE, "..", "tests", "app", "apps", "mavsdk_mission.py")
KINDS = ("policy", "paced", "app")
#: % of CPU the front-end may add to the same flight flown by a Policy (the medians)
TARGET_PCT = 25.0


#: the front-end's thread CPU of the flight being flown (``_instrument``)
_ACC = {"decide": 0.0, "telemetry": 0.0, "link": 0.0}


def _instrument(acc: dict) -> None:
    """Count the thread CPU time spent in the front-end's own code into ``acc``:
    ``decide`` (Autopilot.decide on the simulation thread: commands, the mission, pacing,
    telemetry, and the pre-flight wait), ``telemetry`` (its part in Autopilot._telemetry)
    and ``link`` (the link's wall-clock thread). Wrappers on this interpreter's classes,
    for this benchmark only."""
    from pytest_flockai.app import autopilot, mavlink_udp

    def timed(cls, name, key):
        inner = getattr(cls, name)
        if getattr(inner, "_timed", False):
            return

        def wrapper(*a, **k):
            c = time.thread_time()
            try:
                return inner(*a, **k)
            finally:
                acc[key] += time.thread_time() - c
        wrapper._timed = True           # type: ignore[attr-defined]
        setattr(cls, name, wrapper)

    timed(autopilot.Autopilot, "decide", "decide")
    timed(autopilot.Autopilot, "_telemetry", "telemetry")
    timed(mavlink_udp.Link, "_serve", "link")


def _flights(speed: float) -> dict:
    """One round in this interpreter: {kind: (CPU s, simulated s, wall s, app CPU s)}, and
    ``frontend``: {decide, telemetry, link} CPU s of the app flight's front-end."""
    import pytest_flockai as fa
    from pytest_flockai.app import autopilot
    from pytest_flockai.control.pilots import Waypoints

    nap = getattr(autopilot, "SLEEP_MIN_S", 0.005)

    class Idle(fa.Policy):
        def __init__(self, pace: float):
            super().__init__("idle", period_s=autopilot.PERIOD_S)
            self.pace = pace

        def start(self, run):
            self.w0 = None

        def decide(self, t, drone):
            if self.pace <= 0:
                return
            now = time.monotonic()
            if self.w0 is None:
                self.w0 = now - t / self.pace
            ahead = self.w0 + t / self.pace - now
            if ahead > nap:
                time.sleep(ahead)

    drone = fa.drone("dji-mavic-2-pro")
    pts = [(0.0, 20.0, 10.0), (15.0, 20.0, 10.0), (15.0, 0.0, 8.0)]
    out: dict = {}
    acc = _ACC
    _instrument(acc)
    fa.Mission(drone, Waypoints(pts, 5.0), fly_on="estimate", policies=[Idle(0.0)]).run()
    for kind in KINDS:          # after a flight not measured: each on warm imports and caches
        ch0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        c0, w0 = time.process_time(), time.perf_counter()
        if kind == "app":
            acc.update(dict.fromkeys(acc, 0.0))
            r = fa.app.run([sys.executable, APP], drone, speed=speed, timeout_s=300)
            out["frontend"] = dict(acc)
            assert r.exit_code == 0, r.output
            sim = r.result.scenario["sim_time_s"]
        else:
            m = fa.Mission(drone, Waypoints(pts, 5.0), fly_on="estimate",
                           policies=[Idle(speed if kind == "paced" else 0.0)])
            sim = m.run().scenario["sim_time_s"]
        cpu, wall = time.process_time() - c0, time.perf_counter() - w0
        ch1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        app_cpu = (ch1.ru_utime + ch1.ru_stime) - (ch0.ru_utime + ch0.ru_stime)
        out[kind] = (cpu, sim, wall, app_cpu)
    return out


def _fe(r: dict) -> float:
    """ms of the front-end's own CPU per simulated second of the app flight."""
    f = r["frontend"]
    return 1000 * (f["decide"] + f["link"]) / r["app"][1]


def _round_in(path: str, speed: float) -> dict:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([path, os.environ.get("PYTHONPATH", "")]))
    p = subprocess.run([sys.executable, os.path.abspath(__file__), "--speed", str(speed),
                        "--one-round"], env=env, capture_output=True, text=True, check=True)
    return json.loads(p.stdout.strip().splitlines()[-1])


def _load() -> str:
    return "load average " + " ".join(f"{x:.2f}" for x in os.getloadavg())


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--speed", type=float, default=20.0)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--against", default=None, help="a directory holding another pytest_flockai")
    ap.add_argument("--one-round", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.one_round:
        print(json.dumps(_flights(a.speed)))
        return
    sides = {"this": os.path.abspath(os.path.join(HERE, ".."))}
    if a.against:
        sides["against"] = os.path.abspath(a.against)
    rows: dict = {s: [] for s in sides}
    print(f"speed {a.speed:g}x, {a.rounds} round(s); {_load()}")
    for i in range(a.rounds):
        for side, path in sides.items():
            r = _round_in(path, a.speed) if a.against else _flights(a.speed)
            rows[side].append(r)
            ms = {k: 1000 * r[k][0] / r[k][1] for k in KINDS}
            print(f"round {i + 1} {side:7s}: policy {ms['policy']:.2f}, paced {ms['paced']:.2f}, "
                  f"app {ms['app']:.2f} ms CPU per simulated s (app flight {r['app'][1]:.1f} "
                  f"simulated s in {r['app'][2]:.1f} wall s; the app's own process "
                  f"{r['app'][3]:.2f} CPU s); front-end's own code {_fe(r):.2f} ms per "
                  f"simulated s; {_load()}", flush=True)
    for side, rs in rows.items():
        per = {k: [1000 * r[k][0] / r[k][1] for r in rs] for k in KINDS}
        best = {k: min(v) for k, v in per.items()}
        med = {k: statistics.median(v) for k, v in per.items()}
        print(f"{side} ({sides[side]}):")
        for k in KINDS:
            print(f"  {k:6s} best {best[k]:6.2f}  median {med[k]:6.2f} ms CPU per simulated s")
        for base, what in (("policy", "the unpaced policy flight"),
                           ("paced", f"the paced policy flight at {a.speed:g}x (real time alone)")):
            over = 100 * (med["app"] / med[base] - 1)
            print(f"  overhead over {what}: median {over:+.0f} % (best {100 * (best['app'] / best[base] - 1):+.0f} %): "
                  f"{'PASS' if over <= TARGET_PCT else 'FAIL'} against the {TARGET_PCT:g} % target")
        print(f"  pacing alone (paced over policy): median {100 * (med['paced'] / med['policy'] - 1):+.0f} %")
        fe = {k: statistics.median(1000 * r["frontend"][k] / r["app"][1] for r in rs)
              for k in ("decide", "telemetry", "link")}
        own = statistics.median(_fe(r) for r in rs)
        print(f"  the front-end's own code (thread CPU in Autopilot.decide and the link thread): "
              f"median {own:.2f} ms per simulated s ({100 * own / med['paced']:.0f} % of the "
              f"paced policy flight): decide {fe['decide']:.2f} (telemetry {fe['telemetry']:.2f}), "
              f"link thread {fe['link']:.2f} (its pacing's wake-ups included, which the paced "
              f"policy flight pays in its own step)")


if __name__ == "__main__":
    main()
