"""Closed-loop KPIs, scored against the simulator's truth after the flight.

The perception policies never read the truth to decide; ``Log`` keeps, beside
them, the drone's true ground position at every policy step and the times and
estimated places of what the policy found, and ``kpis`` compares them with
where the targets really were:

- ``time_to_detect_s``: start of the pilot's plan to the first confirmed target;
- ``track_error_p95_m`` / ``track_error_mean_m``: horizontal distance between the
  drone and the followed target while following (95th percentile, mean); the
  target is the actor ``Follow(score=...)`` names, else the target nearest to
  where the track was first confirmed;
- ``track_lost_count`` / ``track_lost_s``: tracks lost, time spent lost;
- ``targets_found``: distinct targets (actors of the target class, else the
  world's objects of that class) within ``MATCH_M`` of a place found;
  ``time_to_find_all_s``: plan start to the last of them (NaN unless all found).
"""

from __future__ import annotations

import math

import numpy as np

from ..ml.metrics import percentile
from ..world.truth import CLASSES

#: m: a place found this close to a target found that target
MATCH_M = 5.0


class Log:
    """The truth beside a policy (see the module docstring)."""

    def __init__(self, run):
        self._st, self._run = run.vehicle, run
        self.samples: list = []       # (t, drone x, drone y)
        self.finds: list = []         # (t, x, y) estimated places found

    def sample(self, t: float) -> None:
        q = self._st.q
        self.samples.append((t, q[0], q[1]))

    def found(self, t: float, xy) -> None:
        self.finds.append((t, float(xy[0]), float(xy[1])))

    # -- scoring ---------------------------------------------------------------
    def _targets(self, cls: str):
        """[(name, fn(t) -> (x, y))] of the possible targets of class ``cls``."""
        actors = getattr(self._run, "actors", None)
        kind = "person" if cls == "person" else "vehicle"
        out = []
        if actors is not None:
            for i, a in enumerate(actors.actors):
                if a.kind == kind:
                    out.append((a.name or f"actor{i}", (lambda t, a=a: a.at(t)[:2])))
        if out:
            return out
        w = self._run.plan.world
        pts = (getattr(w, "people", np.zeros((0, 3))) if cls == "person"
               else getattr(w, "vehicles", np.zeros((0, 4))))
        return [(f"{cls}{i}", (lambda t, p=p: (float(p[0]), float(p[1])))) for i, p in enumerate(pts)]

    def kpis(self, policy, run) -> dict:
        t_plan = next((e["t"] for e in run.events.items
                       if e["kind"] == "stage" and e.get("stage") == "pilot"), math.nan)
        cls = getattr(policy, "target", CLASSES[0])
        targets = self._targets(cls)
        out = {"time_to_detect_s": (self.finds[0][0] - t_plan) if self.finds else math.nan}
        if hasattr(policy, "lost_count"):
            out.update(self._tracking(policy, run, targets))
        else:
            out.update(self._search(targets, t_plan))
        return out

    def _tracking(self, policy, run, targets) -> dict:
        spans = _spans(run.events.items, policy.name, "follow", run.data.time)
        err = []
        target = None
        if self.finds and targets:
            if policy.score is not None:
                target = next((fn for n, fn in targets if n == policy.score), None)
            if target is None:
                t0, x0, y0 = self.finds[0]
                target = min(targets, key=lambda nt: math.dist(nt[1](t0), (x0, y0)))[1]
        if target is not None:
            for t, x, y in self.samples:
                if any(a <= t < b for a, b in spans):
                    err.append(math.dist((x, y), target(t)))
        return {"track_error_p95_m": percentile(err, 95),
                "track_error_mean_m": float(np.mean(err)) if err else math.nan,
                "track_lost_count": float(policy.lost_count),
                "track_lost_s": float(policy._time_in.get("lost", 0.0))}

    def _search(self, targets, t_plan) -> dict:
        found: dict = {}
        for t, x, y in self.finds:
            if not targets:
                break
            name, fn = min(targets, key=lambda nt: math.dist(nt[1](t), (x, y)))
            if math.dist(fn(t), (x, y)) <= MATCH_M and name not in found:
                found[name] = t
        all_found = bool(targets) and len(found) == len(targets)
        return {"targets_found": float(len(found)),
                "time_to_find_all_s": (max(found.values()) - t_plan) if all_found else math.nan}


def _spans(events, policy: str, mode: str, t_end: float) -> list:
    """[(t0, t1)] when ``policy`` was in ``mode`` (from its policy_mode events)."""
    out, start = [], None
    for e in events:
        if e["kind"] != "policy_mode" or e.get("policy") != policy:
            continue
        if e["mode"] == mode and start is None:
            start = e["t"]
        elif e["mode"] != mode and start is not None:
            out.append((start, e["t"]))
            start = None
    if start is not None:
        out.append((start, t_end))
    return out


__all__ = ["Log", "MATCH_M"]
