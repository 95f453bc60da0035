"""What a flight was, in a few words: the scenario fields a reader (and the flight
cache's key) cares about, and the difference between two runs of a test.

``summary(scenario)`` -> ``{"drone": "dji-mavic-2-pro", "computer": "jetson-nano-10w",
"model": "detector sha256:1a2b3c4d", "link": "wifi-80211n", "world": "city",
"conditions": "haze 300 m", "seed": "0", ...}``; ``diff(base, new)`` -> the lines
``computer: jetson-nano-10w -> raspberry-pi-4``, which the compare, the Markdown
summary and the dashboard print before any KPI.
"""

from __future__ import annotations

import hashlib
import json

#: the order the fields are printed in
FIELDS = ("drone", "computer", "model", "link", "world", "conditions", "wind", "seed",
          "payload", "battery", "pilot", "fleet")


def _text(v) -> str:
    if isinstance(v, float):
        return f"{v:g}"
    if isinstance(v, (dict, list)):
        return json.dumps(v, sort_keys=True, separators=(",", ":"))[:80]
    return str(v)


def _models(tasks) -> str | None:
    out = []
    for t in tasks or ():
        if not isinstance(t, dict):
            continue
        m = t.get("model") or {}
        name = m.get("name") or m.get("type") or t.get("name")
        digest = m.get("sha256")
        out.append(f"{name}" + (f" sha256:{digest[:8]}" if digest else "")
                   + (f" ({t.get('execution')})" if t.get("execution") else ""))
    return ", ".join(out) or None


def _links(tasks, offload=None) -> str | None:
    names = [str(t["link"]) for t in tasks or () if isinstance(t, dict) and t.get("link")]
    if isinstance(offload, dict) and offload.get("link"):
        names.append(offload["link"])
    return ", ".join(dict.fromkeys(names)) or None


def _drone(d: dict, out: dict) -> None:
    out["drone"] = d.get("name")
    out["computer"] = d.get("device")
    if d.get("payload_kg"):
        out["payload"] = f"{d['payload_kg']:g} kg"
    bat = d.get("battery") or {}
    if bat.get("capacity_mah"):
        out["battery"] = f"{bat['capacity_mah']:g} mAh {bat.get('cells', '')}S".replace(" S", "")


def summary(scenario) -> dict:
    """The few fields of a flight's (or a fleet's) scenario that say what was flown."""
    s = scenario if isinstance(scenario, dict) else {}
    out: dict = {}
    if isinstance(s.get("drone"), dict):
        _drone(s["drone"], out)
    if isinstance(s.get("fleet"), list):
        drones = [f for f in s["fleet"] if isinstance(f, dict)]
        out["fleet"] = f"{len(drones)} drone(s)"
        inner: dict = {}
        for f in drones:
            d = f.get("drone")
            one: dict = {"model": _models(f.get("tasks")), "link": _links(f.get("tasks"))}
            if isinstance(d, dict):
                _drone(d, one)
            else:
                one["drone"] = d
            one = {k: v for k, v in one.items() if v}
            for k, v in one.items():
                inner.setdefault(k, [])
                if v not in inner[k]:
                    inner[k].append(v)
        out.update({k: ", ".join(str(x) for x in v) for k, v in inner.items()})
    tasks = s.get("tasks")
    out["model"] = _models(tasks) or out.get("model")
    out["link"] = _links(tasks, s.get("offload")) or out.get("link")
    world = s.get("world")
    out["world"] = world.get("name") if isinstance(world, dict) else world
    cond = s.get("conditions")
    if cond:
        out["conditions"] = _text({k: v for k, v in cond.items() if v not in (None, 0, 0.0)}
                                  if isinstance(cond, dict) else cond)
    if s.get("wind"):
        out["wind"] = _text(s["wind"])
    if "seed" in s:
        out["seed"] = s.get("seed")
    pilot = s.get("pilot")
    if isinstance(pilot, dict):
        out["pilot"] = _pilot(pilot)
    return {k: _text(out[k]) for k in FIELDS if out.get(k) not in (None, "")}


def _pilot(p: dict) -> str:
    """``Hover(altitude=10, duration=6, yaw=0)``, so that a changed waypoint or duration is
    a scenario change; past 72 characters, the type and a hash of its settings."""
    args = ", ".join(f"{k}={_text(v)}" for k, v in p.items() if k != "type")
    text = f"{p.get('type')}({args})"
    if len(text) <= 72:
        return text
    blob = json.dumps(p, sort_keys=True, default=str).encode()
    return f"{p.get('type')} sha256:{hashlib.sha256(blob).hexdigest()[:8]}"


def diff(base: dict | None, new: dict | None) -> list[str]:
    """``["computer: jetson-nano-10w -> raspberry-pi-4", ...]`` between two summaries."""
    if not base or not new:
        return []
    out = []
    for k in FIELDS:
        a, b = base.get(k), new.get(k)
        if a != b:
            out.append(f"{k}: {a if a is not None else '-'} -> {b if b is not None else '-'}")
    return out


def of_report(doc: dict) -> dict:
    """``{nodeid: {flight: summary}}`` of a JSON report (``pytest-flockai/1``) or of a
    baseline that kept them (``scenarios``); {} for one without."""
    if not isinstance(doc, dict):
        return {}
    if isinstance(doc.get("scenarios"), dict):
        return doc["scenarios"]
    out: dict = {}
    for t in doc.get("tests") or () if isinstance(doc.get("tests"), list) else ():
        flights = {f.get("name"): summary(f.get("scenario")) for f in t.get("flights") or ()
                   if isinstance(f, dict) and f.get("scenario")}
        if flights:
            out[t.get("nodeid")] = flights
    return out


def changes_of(base: dict, new: dict, test: str) -> list[str]:
    """The scenario changes of one test across its flights (each line once)."""
    b, n = base.get(test) or {}, new.get(test) or {}
    lines: list = []
    for flight in sorted(set(b) & set(n)):
        for line in diff(b[flight], n[flight]):
            if line not in lines:
                lines.append(line)
    return lines
