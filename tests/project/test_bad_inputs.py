"""The bad-input corpus: every public entry point answers bad input
with a ``ConfigError`` (``ReportError``, a bad report or baseline file, is a
documented subclass) whose message names the field and the value; nothing raw
(TypeError, AttributeError, UnicodeDecodeError, numpy errors) escapes.

One case per line: ``(id, call, (field, value))``. ``call(c)`` gets a context
``c`` with ``c.tmp`` (a folder), ``c.flown`` (a short real flight) and helpers;
``field`` and ``value`` are substrings the message must contain.
"""

import json
import math
import os
from fractions import Fraction
from pathlib import Path

import pytest

import pytest_flockai as fa
from pytest_flockai import budgets, cli
from pytest_flockai.cache import FlightCache, default_key
from pytest_flockai.cache.entry import CorruptEntry, read_entry, unseal
from pytest_flockai.errors import ConfigError, WriteError
from pytest_flockai.ml import OnnxModel, OpenCVModel, PythonModel
from pytest_flockai.probes import EnergyProbe
from pytest_flockai.reports import files as report

ROOT = Path(__file__).resolve().parents[2]
BLUEPRINT = ROOT / "pytest_flockai" / "airframe" / "blueprints" / "crazyflie-2-1.toml"
DETECTOR = ROOT / "fixtures" / "models" / "detector.onnx"
CF = fa.drone("crazyflie-2-1")
HOVER = fa.pilots.Hover(1.0, 0.5)
AREA = ((0, 0), (100, 100))


def M(**kw):
    """A Mission of the crazyflie hovering, with the given arguments."""
    drone, pilot = kw.pop("drone", CF), kw.pop("pilot", HOVER)
    return fa.Mission(drone, pilot, **kw)


def T(**kw):
    return fa.Task(PythonModel(lambda f: 0.0, macs=1000), **kw)


class Duck:
    """A duck-typed model whose ``macs`` is not a count."""
    macs = "lots"
    name = "duck"

    def __call__(self, frame):
        return 0.0


class Ctx:
    def __init__(self, tmp: Path, flown):
        self.tmp, self.flown = tmp, flown

    def file(self, name: str, data) -> Path:
        p = self.tmp / name
        p.write_bytes(data if isinstance(data, bytes) else data.encode())
        return p

    def blueprint(self, old: str, new: str, name="bp.toml") -> Path:
        text = BLUEPRINT.read_text()
        assert old in text
        return self.file(name, text.replace(old, new, 1))

    def fifo(self, name: str) -> Path:
        p = self.tmp / name
        os.mkfifo(p)
        return p

    def link(self, name: str, target) -> Path:
        p = self.tmp / name
        os.symlink(target, p)
        return p

    def folder(self, name: str) -> Path:
        p = self.tmp / name
        p.mkdir()
        return p

    def saved(self, ext: str) -> Path:
        return self.flown.save(self.tmp / f"saved{ext}")

    def truncated_csv(self) -> Path:
        p = self.saved(".csv")
        lines = p.read_text().splitlines(keepends=True)
        p.write_text("".join(lines[: len(lines) // 2]))
        return p

    def tampered_sidecar(self) -> Path:
        p = self.saved(".csv")
        side = p.with_name(p.name + ".json")
        head = json.loads(side.read_text())
        head["kpis"]["energy_total_j"] = -5.0
        side.write_text(json.dumps(head))
        return p

    def swapped_pair(self) -> Path:
        """New telemetry with the sidecar of another save (an interrupted save)."""
        p = self.saved(".csv")
        side = p.with_name(p.name + ".json").read_text()
        res = fa.Mission(CF, fa.pilots.Hover(1.0, 0.3), until=2.0).run()
        res.save(p)
        p.with_name(p.name + ".json").write_text(side)
        return p

    def jsonl_edit(self, edit) -> Path:
        p = self.saved(".jsonl")
        lines = p.read_text().splitlines(keepends=True)
        p.write_text(edit(lines))
        return p

    def baseline(self, data) -> Path:
        return self.file("base.json", json.dumps(data))


def _onnx(**kw):
    return lambda c: OnnxModel(DETECTOR, **kw)


CASES = [
    # -- blueprint files, through fa.drone(path) ----------------------------------------------
    ("bp-not-utf8", lambda c: fa.drone(c.file("latin.toml", b"name = 'caf\xe9'\n")), ("not UTF-8", "latin.toml")),
    ("bp-folder", lambda c: fa.drone(c.folder("dir.toml")), ("cannot be read", "dir.toml")),
    ("bp-missing", lambda c: fa.drone(c.tmp / "missing.toml"), ("does not exist", "missing.toml")),
    ("bp-not-toml", lambda c: fa.drone(c.file("bad.toml", "name = = 1\n")), ("not valid TOML", "bad.toml")),
    ("bp-empty", lambda c: fa.drone(c.file("empty.toml", "")), ("name", "empty.toml")),
    ("bp-unknown-name", lambda c: fa.drone("dji-mavic"), ("blueprint", "'dji-mavic'")),
    ("bp-none", lambda c: fa.drone(None), ("blueprint", "'None'")),
    ("bp-mass-string", lambda c: fa.drone(c.blueprint("mass_kg = 0.027", 'mass_kg = "light"')), ("mass_kg", "'light'")),
    ("bp-mass-negative", lambda c: fa.drone(c.blueprint("mass_kg = 0.027", "mass_kg = -1.0")), ("mass_kg", "-1.0")),
    ("bp-capacity-list", lambda c: fa.drone(c.blueprint("capacity_mah = 250.0", "capacity_mah = [250]")), ("capacity_mah", "[250]")),
    ("bp-inertia-short", lambda c: fa.drone(c.blueprint("inertia_kg_m2 = [1.4e-5, 1.4e-5, 2.17e-5]", "inertia_kg_m2 = [1.4e-5]")), ("inertia_kg_m2", "1.4e-05")),
    ("bp-layout", lambda c: fa.drone(c.blueprint('layout = "x"', 'layout = "v"')), ("layout", "'v'")),
    ("bp-usable-fraction", lambda c: fa.drone(c.blueprint("usable_fraction = 0.90", "usable_fraction = 1.5")), ("usable_fraction", "1.5")),
    ("bp-rotor-count", lambda c: fa.drone(c.blueprint("rotor_count = 4", "rotor_count = 0")), ("rotor_count", "0")),
    # -- overrides, through fa.drone(name, **overrides) -------------------------------------
    ("ov-mass-string", lambda c: fa.drone("crazyflie-2-1", mass_kg="heavy"), ("mass_kg", "'heavy'")),
    ("ov-battery-none", lambda c: fa.drone("crazyflie-2-1", battery_mah=None), ("capacity_mah", "None")),
    ("ov-battery-list", lambda c: fa.drone("crazyflie-2-1", battery_mah=[1]), ("capacity_mah", "[1]")),
    ("ov-battery-negative", lambda c: fa.drone("crazyflie-2-1", battery_mah=-100), ("capacity_mah", "-100")),
    ("ov-payload-nan", lambda c: fa.drone("crazyflie-2-1", payload_kg=math.nan), ("payload_kg", "nan")),
    ("ov-device-int", lambda c: fa.drone("crazyflie-2-1", device=5), ("device", "5")),
    ("ov-unknown", lambda c: fa.drone("crazyflie-2-1", names="gps"), ("override", "'names'")),
    ("ov-physics-string", lambda c: fa.drone("crazyflie-2-1", physics_hz="fast"), ("physics_hz", "'fast'")),
    ("ov-control-bool", lambda c: fa.drone("crazyflie-2-1", control_hz=True), ("control_hz", "True")),
    ("ov-voltage-zero", lambda c: fa.drone("crazyflie-2-1", battery_v=0), ("voltage_v", "0")),
    # -- pilots ---------------------------------------------------------------------------------
    ("hover-alt-zero", lambda c: fa.pilots.Hover(0), ("altitude", "0")),
    ("hover-alt-string", lambda c: fa.pilots.Hover("10"), ("altitude", "'10'")),
    ("hover-alt-nan", lambda c: fa.pilots.Hover(math.nan), ("altitude", "nan")),
    ("hover-alt-huge", lambda c: fa.pilots.Hover(1e9), ("altitude", "1e+09")),
    ("hover-duration-negative", lambda c: fa.pilots.Hover(10, -1), ("duration", "-1")),
    ("hover-yaw-string", lambda c: fa.pilots.Hover(10, yaw="north"), ("yaw", "'north'")),
    ("wp-empty", lambda c: fa.pilots.Waypoints([]), ("points", "[]")),
    ("wp-not-list", lambda c: fa.pilots.Waypoints(5), ("points", "5")),
    ("wp-2d-point", lambda c: fa.pilots.Waypoints([(0, 0)]), ("points[0]", "(0, 0)")),
    ("wp-below-ground", lambda c: fa.pilots.Waypoints([(0, 0, -1)]), ("points[0]", "-1")),
    ("wp-string-coordinate", lambda c: fa.pilots.Waypoints([("a", 0, 10)]), ("points[0][0]", "'a'")),
    ("wp-speed-zero", lambda c: fa.pilots.Waypoints([(0, 0, 10)], speed=0), ("speed", "0")),
    ("wp-loop-string", lambda c: fa.pilots.Waypoints([(0, 0, 10)], loop="yes"), ("loop", "'yes'")),
    ("wp-far-away", lambda c: fa.pilots.Waypoints([(1e7, 0, 10)]), ("points[0] x", "1e+07")),
    ("wp-too-many", lambda c: fa.pilots.Waypoints([(0, 0, 10)] * 100_001), ("len(points)", "100001")),
    ("zz-area-int", lambda c: fa.pilots.ZigZag(5), ("area", "5")),
    ("zz-area-flat", lambda c: fa.pilots.ZigZag(((0, 0), (0, 100))), ("area", "((0, 0), (0, 100))")),
    ("zz-area-string", lambda c: fa.pilots.ZigZag((("a", 0), (10, 10))), ("area x0", "'a'")),
    ("zz-area-huge", lambda c: fa.pilots.ZigZag(((0, 0), (1e9, 100))), ("area x1", "1e+09")),
    ("zz-spacing-zero", lambda c: fa.pilots.ZigZag(AREA, spacing=0), ("spacing", "0")),
    ("zz-spacing-negative", lambda c: fa.pilots.ZigZag(AREA, spacing=-5), ("spacing", "-5")),
    ("zz-spacing-micrometre", lambda c: fa.pilots.ZigZag(AREA, spacing=1e-6), ("spacing", "1e-06")),
    ("zz-altitude-zero", lambda c: fa.pilots.ZigZag(AREA, altitude=0), ("altitude", "0")),
    ("zz-speed-inf", lambda c: fa.pilots.ZigZag(AREA, speed=math.inf), ("speed", "inf")),
    ("orbit-radius-zero", lambda c: fa.pilots.Orbit(radius=0), ("radius", "0")),
    ("orbit-radius-huge", lambda c: fa.pilots.Orbit(radius=1e9), ("radius", "1e+09")),
    ("orbit-center-short", lambda c: fa.pilots.Orbit(center=(0,)), ("center", "(0,)")),
    ("orbit-laps-zero", lambda c: fa.pilots.Orbit(laps=0), ("laps", "0")),
    ("orbit-speed-negative", lambda c: fa.pilots.Orbit(speed=-1), ("speed", "-1")),
    ("orbit-altitude-string", lambda c: fa.pilots.Orbit(altitude="x"), ("altitude", "'x'")),
    # -- Mission ----------------------------------------------------------------------------------
    ("m-drone-string", lambda c: M(drone="dji"), ("drone", "'dji'")),
    ("m-pilot-string", lambda c: M(pilot="hover"), ("pilot", "'hover'")),
    ("m-pilot-none", lambda c: M(pilot=None), ("pilot", "None")),
    ("m-seed-negative", lambda c: M(seed=-1), ("seed", "-1")),
    ("m-seed-float", lambda c: M(seed=1.5), ("seed", "1.5")),
    ("m-seed-bool", lambda c: M(seed=True), ("seed", "True")),
    ("m-name-empty", lambda c: M(name=""), ("name", "''")),
    ("m-name-int", lambda c: M(name=5), ("name", "5")),
    ("m-world-string", lambda c: M(world="urban"), ("world", "'urban'")),
    ("m-world-int", lambda c: M(world=5), ("world", "5")),
    ("m-until-word", lambda c: M(until="forever"), ("until", "'forever'")),
    ("m-until-zero", lambda c: M(until=0), ("until", "0")),
    ("m-until-nan", lambda c: M(until=math.nan), ("until", "nan")),
    ("m-until-list", lambda c: M(until=[1]), ("until", "[1]")),
    ("m-until-bool", lambda c: M(until=True), ("until", "True")),
    ("m-until-above-max-time", lambda c: M(until=1e12), ("until", "1e+12")),
    ("m-max-time-above-limit", lambda c: M(max_time_s=1e9), ("max_time_s", "1e+09")),
    ("m-max-time-zero", lambda c: M(max_time_s=0), ("max_time_s", "0")),
    ("m-telemetry-hz-zero", lambda c: M(telemetry_hz=0), ("telemetry_hz", "0")),
    ("m-telemetry-rows", lambda c: M(telemetry_hz=1e6), ("telemetry_hz", "1e+06")),
    ("m-energy-hz-negative", lambda c: M(energy_hz=-1), ("energy_hz", "-1")),
    ("m-climb-zero", lambda c: M(climb_speed=0), ("climb_speed", "0")),
    ("m-descent-nan", lambda c: M(descent_speed=math.nan), ("descent_speed", "nan")),
    ("m-fly-on", lambda c: M(fly_on="gps"), ("fly_on", "'gps'")),
    ("m-dataset-dir-int", lambda c: M(dataset_dir=5), ("dataset_dir", "5")),
    ("m-dataset-period-zero", lambda c: M(dataset_period_s=0), ("dataset_period_s", "0")),
    ("m-tasks-int", lambda c: M(tasks=5), ("tasks", "5")),
    ("m-tasks-string", lambda c: M(tasks=["count"]), ("tasks[0]", "'count'")),
    ("m-sensors-int", lambda c: M(sensors=5), ("sensors", "5")),
    ("m-sensors-string", lambda c: M(sensors=["gps"]), ("sensors[0]", "'gps'")),
    ("m-components-int", lambda c: M(components=3), ("components", "3")),
    ("m-components-object", lambda c: M(components=[object()]), ("components[0]", "object")),
    ("m-probes-int", lambda c: M(probes=5), ("probes", "5")),
    ("m-probes-string", lambda c: M(probes=["energy"]), ("probes", "'energy'")),
    ("m-probe-samples", lambda c: M(probes=[EnergyProbe(period_s=1e-4)], until=3600), ("probe 'energy'", "0.0001 s")),
    ("m-conditions-string", lambda c: M(conditions="haze"), ("conditions", "'haze'")),
    ("m-return-home-string", lambda c: M(return_home="no"), ("return_home", "'no'")),
    ("m-max-wall-zero", lambda c: M(max_wall_s=0), ("max_wall_s", "0")),
    ("m-max-wall-string", lambda c: M(max_wall_s="1"), ("max_wall_s", "'1'")),
    ("m-wind-string", lambda c: M(wind="strong"), ("wind", "'strong'")),
    ("m-wind-huge", lambda c: M(wind=1e6), ("mean", "1e+06")),
    ("m-wind-nan", lambda c: M(wind=math.nan), ("mean[0]", "nan")),
    ("m-camera-task-without-camera", lambda c: M(tasks=[T()]), ("sensor 'camera'", "crazyflie-2-1")),
    ("m-subscribe-int", lambda c: M().subscribe(5), ("subscribe", "5")),
    # -- Wind -------------------------------------------------------------------------------------
    ("wind-scalar-mean", lambda c: fa.Wind(5), ("mean", "5")),
    ("wind-2d", lambda c: fa.Wind((1, 2)), ("mean", "(1, 2)")),
    ("wind-nan", lambda c: fa.Wind((math.nan, 0, 0)), ("mean[0]", "nan")),
    ("wind-gust-negative", lambda c: fa.Wind((5, 0, 0), gust_std=-1), ("gust_std", "-1")),
    ("wind-tau-zero", lambda c: fa.Wind((5, 0, 0), gust_tau_s=0), ("gust_tau_s", "0")),
    ("wind-hurricane", lambda c: fa.Wind((200, 0, 0)), ("mean", "200")),
    ("wind-gust-huge", lambda c: fa.Wind((5, 0, 0), gust_std=1e6), ("gust_std", "1e+06")),
    # -- World ------------------------------------------------------------------------------------
    ("urban-seed-negative", lambda c: fa.World.urban(seed=-1), ("seed", "-1")),
    ("urban-seed-string", lambda c: fa.World.urban(seed="a"), ("seed", "'a'")),
    ("urban-size-small", lambda c: fa.World.urban(size=(10, 10)), ("size", "10")),
    ("urban-size-huge", lambda c: fa.World.urban(size=(1e6, 1e6)), ("size", "1e+06")),
    ("urban-size-int", lambda c: fa.World.urban(size=5), ("size", "5")),
    ("urban-people-negative", lambda c: fa.World.urban(people=-1), ("people", "-1")),
    ("urban-people-float", lambda c: fa.World.urban(people=1.5), ("people", "1.5")),
    ("urban-people-million", lambda c: fa.World.urban(people=10**6), ("people", "1e+06")),
    ("urban-vehicles-negative", lambda c: fa.World.urban(vehicles=-1), ("vehicles", "-1")),
    ("urban-vehicles-million", lambda c: fa.World.urban(vehicles=10**6), ("vehicles", "1e+06")),
    ("urban-density", lambda c: fa.World.urban(building_density=2), ("building_density", "2")),
    ("urban-clear-negative", lambda c: fa.World.urban(clear_radius=-1), ("clear_radius", "-1")),
    ("urban-height-zero", lambda c: fa.World.urban(max_building_height=0), ("max_building_height", "0")),
    ("urban-crowds-int", lambda c: fa.World.urban(crowds=5), ("crowds", "5")),
    ("urban-crowd-short", lambda c: fa.World.urban(crowds=[(0, 0, 10)]), ("crowds[0]", "(0, 0, 10)")),
    ("urban-crowd-outside", lambda c: fa.World.urban(crowds=[(1e6, 0, 10, 5)]), ("crowds[0].x", "1000000.0")),
    ("urban-crowd-too-dense", lambda c: fa.World.urban(crowds=[(0, 0, 10_000, 1)]), ("crowds[0].count", "10000")),
    ("urban-crowds-too-many", lambda c: fa.World.urban(size=(2000, 2000), people=2_000, crowds=[(0, 0, 2000, 50)]), ("people", "4000")),
    ("scene-people-int", lambda c: fa.World.scene(people=5), ("people", "5")),
    ("scene-people-3d", lambda c: fa.World.scene(people=[(0, 0, 0)]), ("people", "(0, 0, 0)")),
    ("scene-people-nan", lambda c: fa.World.scene(people=[(math.nan, 0)]), ("people", "non-finite")),
    ("scene-size-huge", lambda c: fa.World.scene(size=(1e7, 100)), ("size", "1e+07")),
    ("mjcf-int", lambda c: fa.World.from_mjcf(5), ("path", "5")),
    ("mjcf-missing", lambda c: fa.World.from_mjcf(c.tmp / "none.xml"), ("path", "none.xml")),
    ("mjcf-garbage", lambda c: fa.World.from_mjcf(c.file("scene.xml", "<mujoco><worldbody>")), ("path", "scene.xml")),
    # -- Task -------------------------------------------------------------------------------------
    ("task-model-int", lambda c: fa.Task(5), ("model", "5")),
    ("task-name-dot", lambda c: T(name="a.b"), ("name", "'a.b'")),
    ("task-name-empty", lambda c: T(name=""), ("name", "''")),
    ("task-sensor-int", lambda c: T(sensor=5), ("sensor", "5")),
    ("task-period-zero", lambda c: T(period_s=0), ("period_s", "0")),
    ("task-period-string", lambda c: T(period_s="5"), ("period_s", "'5'")),
    ("task-execution", lambda c: T(execution="cloud"), ("execution", "'cloud'")),
    ("task-device-name", lambda c: T(device="pi"), ("device", "'pi'")),
    ("task-device-int", lambda c: T(device=5), ("device", "5")),
    ("task-link", lambda c: T(link="5g"), ("link", "'5g'")),
    ("task-on-busy", lambda c: T(on_busy="wait"), ("on_busy", "'wait'")),
    ("task-latency", lambda c: T(latency="fast"), ("latency", "'fast'")),
    ("task-result-bytes", lambda c: T(result_bytes=-1), ("result_bytes", "-1")),
    ("task-jpeg-quality", lambda c: T(jpeg_quality=101), ("jpeg_quality", "101")),
    ("task-crowd-threshold", lambda c: T(crowd_threshold=0), ("crowd_threshold", "0")),
    ("task-count-int", lambda c: T(count=5), ("count", "5")),
    ("task-alert", lambda c: T(alert="sms"), ("alert", "'sms'")),
    ("task-ground-station", lambda c: T(ground_station=(0, 0)), ("ground_station", "(0, 0)")),
    ("task-max-queue", lambda c: T(max_queue=0), ("max_queue", "0")),
    ("task-evaluate", lambda c: T(evaluate="map"), ("evaluate", "'map'")),
    ("task-classes-int", lambda c: T(classes=5), ("classes", "5")),
    ("task-classes-empty", lambda c: T(classes=[]), ("classes", "[]")),
    ("task-score-threshold", lambda c: T(score_threshold=2), ("score_threshold", "2")),
    ("task-iou-threshold", lambda c: T(iou_threshold=-1), ("iou_threshold", "-1")),
    ("task-decode", lambda c: T(decode="ssd"), ("decode", "'ssd'")),
    ("task-min-visible", lambda c: T(min_visible=2), ("min_visible", "2")),
    ("task-macs-unknown", lambda c: fa.Task(PythonModel(lambda f: 0)), ("macs", "None")),
    ("task-duck-macs", lambda c: fa.Task(Duck()), ("macs", "'lots'")),
    # -- models -----------------------------------------------------------------------------------
    ("py-fn-int", lambda c: PythonModel(5), ("fn", "5")),
    ("py-macs-negative", lambda c: PythonModel(len, macs=-1), ("macs", "-1")),
    ("py-macs-string", lambda c: PythonModel(len, macs="big"), ("macs", "'big'")),
    ("py-macs-nan", lambda c: PythonModel(len, macs=math.nan), ("macs", "nan")),
    ("py-macs-overflow", lambda c: PythonModel(len, macs=10**400), ("macs", "1000000000")),
    ("py-macs-negative-fraction", lambda c: PythonModel(len, macs=Fraction(-1, 2)), ("macs", "Fraction(-1, 2)")),
    ("py-params-negative", lambda c: PythonModel(len, macs=1, params=-1), ("params", "-1")),
    ("py-params-float", lambda c: PythonModel(len, macs=1, params=1.5), ("params", "1.5")),
    ("cv-macs-none", lambda c: OpenCVModel(len, macs=None), ("macs", "None")),
    ("onnx-int", lambda c: OnnxModel(5), ("path", "5")),
    ("onnx-none", lambda c: OnnxModel(None), ("path", "None")),
    ("onnx-missing", lambda c: OnnxModel(c.tmp / "none.onnx"), ("path", "none.onnx")),
    ("onnx-folder", lambda c: OnnxModel(c.folder("m.onnx")), ("path", "m.onnx")),
    ("onnx-garbage", lambda c: OnnxModel(c.file("g.onnx", b"\xff\x00garbage")), ("path", "g.onnx")),
    ("onnx-layout", _onnx(layout="NCWH"), ("layout", "'NCWH'")),
    ("onnx-input-size", _onnx(input_size=(0, 0)), ("input_size", "(0, 0)")),
    ("onnx-mean-count", _onnx(mean=[1, 2]), ("mean", "[1, 2]")),
    ("onnx-std-zero", _onnx(std=0), ("std", "0")),
    ("onnx-postprocess", _onnx(postprocess=5), ("postprocess", "5")),
    ("onnx-macs-negative", _onnx(macs=-5), ("macs", "-5")),
    # -- budgets and markers' budgets (budgets.parse / evaluate) ------------------------------------
    ("b-not-string", lambda c: budgets.parse("flight_time_s", 5), ("flight_time_s", "5")),
    ("b-unknown-kpi", lambda c: budgets.parse("flight_tim_s", "<= 1 s"), ("KPI", "'flight_tim_s'")),
    ("b-kpi-int", lambda c: budgets.parse(5, "<= 1 s"), ("KPI name", "5")),
    ("b-kpi-empty", lambda c: budgets.parse("", "<= 1 s"), ("KPI name", "''")),
    ("b-overflow", lambda c: budgets.parse("energy_total_j", "<= 1e999 J"), ("energy_total_j", "'<= 1e999 J'")),
    ("b-400-digits", lambda c: budgets.parse("energy_total_j", "<= " + "9" * 400), ("energy_total_j", "999999")),
    ("b-operator", lambda c: budgets.parse("flight_time_s", "~ 5 s"), ("flight_time_s", "'~ 5 s'")),
    ("b-unit", lambda c: budgets.parse("flight_time_s", "<= 5 parsecs"), ("flight_time_s", "'parsecs'")),
    ("b-dimension", lambda c: budgets.parse("flight_time_s", "<= 5 J"), ("flight_time_s", "'J'")),
    ("b-percent-of-time", lambda c: budgets.parse("flight_time_s", "<= 50%"), ("flight_time_s", "'%'")),
    ("b-no-number", lambda c: budgets.parse("flight_time_s", "<="), ("flight_time_s", "'<='")),
    ("b-nan", lambda c: budgets.parse("flight_time_s", "<= nan s"), ("flight_time_s", "'<= nan s'")),
    ("b-evaluate-list", lambda c: budgets.evaluate({"flight_time_s": 3.0}, ["x"]), ("budgets", "['x']")),
    ("b-evaluate-result", lambda c: budgets.evaluate("abc", flight_time_s="<= 1 s"), ("result", "'abc'")),
    ("b-evaluate-value", lambda c: budgets.evaluate({"flight_time_s": "abc"}, flight_time_s="<= 1 s"), ("flight_time_s", "'abc'")),
    ("b-evaluate-missing", lambda c: budgets.evaluate({"energy_total_j": 1.0}, flight_time_s="<= 1 s"), ("flight_time_s", "energy_total_j")),
    ("b-check-none", lambda c: budgets.check({"flight_time_s": 1.0}, {"flight_time_s": None}), ("flight_time_s", "None")),
    # -- baselines (report.load_baseline; ReportError is a ConfigError) ----------------------------
    ("base-missing", lambda c: report.load_baseline(c.tmp / "none.json"), ("baseline file", "none.json")),
    ("base-not-json", lambda c: report.load_baseline(c.file("base.json", "{nope")), ("not valid JSON", "base.json")),
    ("base-not-utf8", lambda c: report.load_baseline(c.file("base.json", b"\xff\xfe{}")), ("cannot be read", "base.json")),
    ("base-list", lambda c: report.load_baseline(c.baseline([1, 2])), ("baseline file", "list")),
    ("base-schema", lambda c: report.load_baseline(c.baseline({"schema": "x/9", "tests": {}})), ("schema", "'x/9'")),
    ("base-string-value", lambda c: report.load_baseline(c.baseline({"t::a": {"flight": {"energy_total_j": "1"}}})), ("energy_total_j", "'1'")),
    ("base-folder", lambda c: report.load_baseline(c.folder("b.json")), ("baseline file", "b.json")),
    # -- report and artifact paths --------------------------------------------------------------------
    ("report-path-folder", lambda c: report.check_writable(c.folder("r.json"), "--flockai-json"), ("--flockai-json", "r.json")),
    ("report-path-no-parent", lambda c: report.check_writable(c.tmp / "no" / "r.json", "--flockai-json"), ("--flockai-json", "r.json")),
    # -- saved flights (FlightResult.save / load) ------------------------------------------------
    ("save-int", lambda c: c.flown.save(5), ("path", "5")),
    ("save-extension", lambda c: c.flown.save(c.tmp / "f.txt"), ("path", "f.txt")),
    ("load-int", lambda c: fa.FlightResult.load(5), ("path", "5")),
    ("load-none", lambda c: fa.FlightResult.load(None), ("path", "None")),
    ("load-missing", lambda c: fa.FlightResult.load(c.tmp / "none.csv"), ("load", "none.csv")),
    ("load-extension", lambda c: fa.FlightResult.load(c.file("f.txt", "x")), ("load", "f.txt")),
    ("load-folder", lambda c: fa.FlightResult.load(c.folder("f.csv")), ("load", "f.csv")),
    ("load-no-sidecar", lambda c: fa.FlightResult.load(c.file("f.csv", "t,x\n0,1\n")), ("sidecar", "f.csv.json")),
    ("load-sidecar-not-json", lambda c: (c.file("f.csv", "t,x\n0,1\n"), c.file("f.csv.json", "{"), fa.FlightResult.load(c.tmp / "f.csv")), ("cannot read", "f.csv")),
    ("load-sidecar-format", lambda c: (c.file("f.csv", "t,x\n0,1\n"), c.file("f.csv.json", '{"format": "x"}'), fa.FlightResult.load(c.tmp / "f.csv")), ("header", "f.csv.json")),
    ("load-truncated-csv", lambda c: fa.FlightResult.load(c.truncated_csv()), ("sha256", "saved.csv")),
    ("load-tampered-sidecar", lambda c: fa.FlightResult.load(c.tampered_sidecar()), ("sha256", "saved.csv.json")),
    ("load-swapped-pair", lambda c: fa.FlightResult.load(c.swapped_pair()), ("sha256", "saved.csv")),
    ("load-jsonl-truncated", lambda c: fa.FlightResult.load(c.jsonl_edit(lambda ls: "".join(ls[:-3]))), ("sha256", "saved.jsonl")),
    ("load-jsonl-header-list", lambda c: fa.FlightResult.load(c.file("f.jsonl", "[1, 2]\n")), ("header", "f.jsonl")),
    ("load-jsonl-garbage", lambda c: fa.FlightResult.load(c.file("f.jsonl", "garbage\n")), ("cannot read", "f.jsonl")),
    ("load-jsonl-not-utf8", lambda c: fa.FlightResult.load(c.file("f.jsonl", b"\xff\xfe\n")), ("cannot read", "f.jsonl")),
    # -- rates, speeds, periods the simulation cannot honour; raw errors left ---------------
    ("m-energy-hz-slow", lambda c: M(energy_hz=0.01), ("energy_hz", "0.01")),
    ("m-energy-hz-tiny", lambda c: M(energy_hz=1e-9), ("MIN_ENERGY_HZ", "1e-09")),
    ("m-climb-crawl", lambda c: M(climb_speed=1e-6), ("climb_speed", "1e-06")),
    ("m-descent-crawl", lambda c: M(descent_speed=0.01), ("descent_speed", "0.01")),
    ("wp-speed-1e4", lambda c: fa.pilots.Waypoints([(1, 1, 1)], speed=1e4), ("speed", "10000")),
    ("zz-speed-1e9", lambda c: fa.pilots.ZigZag(AREA, speed=1e9), ("speed", "1e+09")),
    ("orbit-speed-huge", lambda c: fa.pilots.Orbit((0, 0), 10, 10, speed=1e3), ("speed", "1000")),
    ("task-period-tiny", lambda c: T(period_s=1e-6), ("period_s", "1e-06")),
    ("bp-usable-fraction-tiny", lambda c: fa.drone("crazyflie-2-1", usable_fraction=1e-300), ("usable_fraction", "1e-300")),
    ("drone-battery-none", lambda c: setattr(fa.drone("crazyflie-2-1"), "battery", None), ("battery", "None")),
    ("drone-rotor-string", lambda c: setattr(fa.drone("crazyflie-2-1"), "rotor", "big"), ("rotor", "'big'")),
    ("fleet-name-fleet", lambda c: fa.FleetDrone("fleet", CF, HOVER), ("name", "'fleet'")),
    ("fleet-name-ground", lambda c: fa.FleetDrone("ground", CF, HOVER), ("name", "'ground'")),
    ("fleet-name-link", lambda c: fa.FleetDrone("Link", CF, HOVER), ("name", "'Link'")),
    ("fleet-pad-in-building", lambda c: fa.Fleet([fa.FleetDrone("a", CF, HOVER, pad=(0, 0))], world=fa.World.scene(buildings=[(0, 0, 5, 5, 6.5)])), ("pad = (0, 0)", "inside")),
    ("fleet-pad-roof-edge", lambda c: fa.Fleet([fa.FleetDrone("a", CF, HOVER, pad=(5.5, 0))], world=fa.World.scene(buildings=[(0, 0, 5, 5, 6.5)])), ("pad = (5.5, 0)", "0.50 m from the wall")),
    ("survey-world-string", lambda c: fa.fleet.survey(AREA, 2, world="city"), ("world", "'city'")),
    ("base-deep", lambda c: report.load_baseline(c.file("deep.json", "[" * 10**5 + "]" * 10**5)), ("MAX_JSON_DEPTH", "deep.json")),
    ("base-fifo", lambda c: report.load_baseline(c.fifo("b.json")), ("not a regular file", "b.json")),
    ("base-report-nodeid-int", lambda c: report.load_baseline(c.baseline({"schema": "pytest-flockai/1", "tests": [{"nodeid": 3}]})), ("malformed report", "nodeid")),
    ("save-onto-folder", lambda c: c.flown.save(c.folder("f.csv")), ("is a folder", "f.csv")),
    ("report-path-device", lambda c: report.check_writable(Path("/dev/null"), "--flockai-md"), ("--flockai-md", "/dev/null")),
    ("cache-mode", lambda c: FlightCache(c.tmp, "sometimes"), ("mode", "'sometimes'")),
    ("cache-key-empty", lambda c: FlightCache(c.tmp, key=""), ("key", "''")),
    ("cache-max-bytes", lambda c: FlightCache(c.tmp, max_bytes=-1), ("max_bytes", "-1")),
    ("cache-verify-fraction", lambda c: FlightCache(c.tmp, verify_fraction=2), ("verify_fraction", "2")),
    ("cli-max-size", lambda c: cli.parse_size("lots"), ("--max-size", "'lots'")),
]

#: bad files and places a write or a cache read meets: a documented error naming the file
#: (WriteError, an OSError and a FlockAIError; the cache's CorruptEntry is a miss)
IO_CASES = [
    ("write-device", lambda c: report.write_json_atomic(Path("/dev/full"), {}), WriteError, "/dev/full"),
    ("write-folder", lambda c: report.write_json_atomic(c.folder("r.json"), {}), WriteError, "r.json"),
    ("write-no-folder", lambda c: report.write_json_atomic(c.tmp / "no" / "r.json", {}), WriteError, "does not exist"),
    ("save-under-a-file", lambda c: c.flown.save(c.file("x", "") / "s" / "r.csv"), WriteError, "cannot create folder"),
    ("cache-entry-fifo", lambda c: read_entry(c.fifo("e.flight")), CorruptEntry, "not a regular file"),
    ("cache-entry-dev-zero", lambda c: read_entry(c.link("e.flight", "/dev/zero")), CorruptEntry, "symlink"),
    ("cache-entry-garbage", lambda c: unseal(b"garbage", "k", default_key()), CorruptEntry, "bad magic"),
]


@pytest.fixture(scope="module")
def flown():
    return fa.Mission(CF, HOVER, until=2.0).run()


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_bad_input_gives_a_config_error_naming_field_and_value(case, tmp_path, flown):
    _, call, (field, value) = case
    with pytest.raises(ConfigError) as info:
        call(Ctx(tmp_path, flown))
    msg = str(info.value)
    assert field in msg and value in msg, msg


@pytest.mark.parametrize("case", IO_CASES, ids=[c[0] for c in IO_CASES])
def test_bad_files_give_a_documented_error_naming_them(case, tmp_path, flown):
    _, call, kind, words = case
    with pytest.raises(kind) as info:
        call(Ctx(tmp_path, flown))
    assert words in str(info.value), str(info.value)


def test_the_corpus_is_large_and_covers_every_entry_point():
    assert len(CASES) >= 120
    assert len({c[0] for c in CASES}) == len(CASES)
    prefixes = {c[0].split("-")[0] for c in CASES}
    assert {"bp", "ov", "hover", "wp", "zz", "orbit", "m", "wind", "urban", "scene", "mjcf",
            "task", "py", "onnx", "b", "base", "report", "save", "load"} <= prefixes


def test_report_error_is_a_documented_config_error():
    assert issubclass(report.ReportError, ConfigError)
    assert "ConfigError" in report.ReportError.__doc__
