"""The FlockAI paper's experiments (Table 2), defined once for the example tests
and for ``paper_table.py``.

Paper setup (section 5): DJI Mavic 2 Pro blueprint, a bounding-box zig-zag
pilot over an urban area, crowd counting from the camera every 5 s
(Listing 2: ``inf_period=5``), on board (Raspberry Pi class computer) or on the
ground station over Wi-Fi. Our world is a simulated city with crowds, so
every frame's people count is known.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest_flockai as fa

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "fixtures" / "models"

# The paper's figures (FlockAI, Future Internet 2021, 13(12), 317: Tables 2-4, section 5).
PAPER = {
    "1-A": {"flight_time_s": 1806, "note": "motors ~91 %, comm ~3 %"},
    "1-B": {"flight_time_s": 1488, "inference_latency_p50_s": 1.36, "note": "proc ~21 %"},
    "2": {"flight_time_s": 1551, "inference_latency_p50_s": 3.15, "note": "comm +16 % vs 1-A"},
    "3-A": {"flight_time_s": 1488, "inference_latency_p50_s": 1.361, "accuracy": 0.95},
    "3-B": {"flight_time_s": 1642, "inference_latency_p50_s": 0.274, "accuracy": 0.60},
}


def world() -> fa.World:
    """A 240 m x 240 m city with 120 scattered people and three crowds; buildings
    kept below the survey altitude."""
    return fa.World.urban(seed=7, size=(240.0, 240.0), people=120,
                          crowds=[(70.0, 50.0, 50, 5.0), (-60.0, 80.0, 40, 4.0), (-80.0, -60.0, 30, 4.0)],
                          max_building_height=25.0)


def survey(full: bool = False):
    """The bounding-box zig-zag over the city (about 4 min); ``full``: repeat it
    until the battery is depleted, as the paper's experiments flew."""
    z = fa.pilots.ZigZag(area=((-100.0, -100.0), (100.0, 100.0)), altitude=35.0, spacing=35.0, speed=8.0)
    if full:
        return fa.pilots.Waypoints(z.points, speed=8.0, loop=True)
    return z


def cnn():
    """The accurate model: fixtures/models/crowd_cnn.onnx (density-map CNN)."""
    return fa.ml.OnnxModel(MODELS / "crowd_cnn.onnx", name="cnn")


def cheap():
    """The cheaper model (the paper's 'FIGs' role): the classical OpenCV blob
    counter, 2.3 M MAC-equivalents (fixtures/models/blob_counter.py). It is
    cheaper and more accurate than the tiny CNN also shipped (see
    fixtures/models/README.md), so it is the one compared with the CNN."""
    sys.path.insert(0, str(MODELS))
    from blob_counter import blob_counter
    return blob_counter()


def tasks(name: str, models: dict) -> list:
    """The ML tasks of each scenario: camera every 5 s (the paper's inf_period=5)."""
    if name == "1-A":
        return []
    if name in ("1-B", "3-A"):
        return [fa.Task(models["cnn"], period_s=5.0, execution="onboard", device="raspberry-pi-4", name="cnn")]
    if name == "2":
        return [fa.Task(models["cnn"], period_s=5.0, execution="remote", link="wifi-80211n", name="cnn")]
    if name == "2-slow":   # the same over the 64 kbit/s telemetry radio
        return [fa.Task(models["cnn"], period_s=5.0, execution="remote", link="sik-915", name="cnn")]
    if name == "3-B":
        return [fa.Task(models["cheap"], period_s=5.0, execution="onboard", device="raspberry-pi-4",
                        name="cheap")]
    raise KeyError(name)


SCENARIOS = ("1-A", "1-B", "2", "2-slow", "3-A", "3-B")


# -- beyond the paper: a person + vehicle detector, scored by the COCO standard ----------
def detection_world() -> fa.World:
    """The paper's city with parked and moving-lane cars added (the people and
    buildings are the same: cars come from their own random stream)."""
    return fa.World.urban(seed=7, size=(240.0, 240.0), people=120,
                          crowds=[(70.0, 50.0, 50, 5.0), (-60.0, 80.0, 40, 4.0), (-80.0, -60.0, 30, 4.0)],
                          max_building_height=25.0, vehicles=60)


def detector():
    """fixtures/models/detector.onnx: people and vehicles, YOLOv8 raw-head output
    (recipe and held-out mAP in fixtures/models/README.md)."""
    return fa.ml.OnnxModel(MODELS / "detector.onnx", name="detector")


DETECTION = {   # name -> Task arguments: the detector every 1 s at 30 m
    "det-pi4": dict(execution="onboard", device="raspberry-pi-4"),
    "det-jetson": dict(execution="onboard", device="jetson-orin-nano"),
    "det-remote": dict(execution="remote", link="wifi-80211n"),
}


def detection_mission(name: str, model, w) -> fa.Mission:
    args = dict(DETECTION[name])
    computer = args.pop("device", None)       # the drone's computer, not a second one
    task = fa.Task(model, period_s=1.0, evaluate="detection", score_threshold=0.4,
                   name="det", **args)
    pilot = fa.pilots.ZigZag(area=((-100.0, -100.0), (100.0, 100.0)), altitude=30.0,
                             spacing=50.0, speed=6.0)
    drone = fa.drone("dji-mavic-2-pro", **({"device": computer} if computer else {}))
    return fa.Mission(drone, pilot, world=w, tasks=[task], seed=0, name=name)


def mission(name: str, models: dict, *, full: bool = False, w=None) -> fa.Mission:
    return fa.Mission(fa.drone("dji-mavic-2-pro"), survey(full), world=w or world(),
                      tasks=tasks(name, models), seed=0, name=name,
                      until="battery_depleted" if full else "landed")
