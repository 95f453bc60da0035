"""Integrity of the published latency table, its sources, the computer datasheets and the
published energy figures (pytest_flockai/compute/data)."""

import csv
import tomllib
from collections import Counter, defaultdict
from pathlib import Path

import pytest

DATA = Path(__file__).resolve().parents[2] / "pytest_flockai" / "compute" / "data"

COMPUTERS = {"raspberry-pi-4", "raspberry-pi-5", "jetson-nano-5w", "jetson-nano-10w", "jetson-orin-nano",
             "jetson-orin-nano-super", "jetson-orin-nx-16gb", "coral-dev-board", "ground-gpu"}
RUNTIMES = {"onnxruntime", "tflite", "ncnn", "openvino", "opencv-dnn", "pytorch", "tensorrt", "edgetpu"}
TARGETS = {"cpu", "gpu", "npu"}
PRECISIONS = {"fp32", "fp16", "int8"}
CLASSIFIERS = {"resnet18", "resnet50", "resnet101", "mobilenet_v1", "mobilenet_v2", "mobilenet_v3_small",
               "mobilenet_v3_large", "efficientnet_b0", "efficientnet_lite0", "squeezenet1_1", "inception_v3",
               "inception_v4", "vgg16", "densenet121", "googlenet", "shufflenet_v2", "alexnet"}
DETECTORS = {"yolov8n", "yolov8s", "yolov8m", "yolov8l", "yolo11n", "yolo11s", "yolo11m", "yolov5nu", "yolov5su",
             "ssd_mobilenet_v1", "ssd_mobilenet_v2", "ssdlite_mobilenet_v3", "yolo11l", "yolov5n", "yolo26n", "yolo26s",
             "yolo26m", "yolo26l", "yolov9t", "yolov9s", "yolov9m", "yolov10n", "yolov10s", "yolov10m"}
NETWORKS = CLASSIFIERS | DETECTORS
LATENCY_COLUMNS = ["row_id", "source_id", "computer", "runtime", "target", "precision", "network", "input",
                   "latency_ms", "table", "row", "notes", "cpu_clock_ghz", "threads"]
SOURCE_COLUMNS = ["source_id", "document", "publisher", "year", "where", "half", "added"]
ENERGY_COLUMNS = ["energy_id", "source_id", "computer", "runtime", "target", "precision", "network", "input",
                  "latency_ms", "power_w", "idle_w", "energy_j", "measured_at", "table", "row", "notes"]


def _read(name, columns):
    with open(DATA / name, newline="") as fh:
        reader = csv.DictReader(fh)
        assert reader.fieldnames == columns, f"{name}: columns {reader.fieldnames}"
        out = list(reader)
    # a field with an unquoted comma shifts the columns after it (DictReader keeps the rest
    # under None): every row must have exactly the header's fields
    bad = [r.get(columns[0]) for r in out if None in r or None in r.values()]
    assert not bad, f"{name}: rows with more or fewer fields than the header: {bad}"
    return out


@pytest.fixture(scope="module")
def rows():
    return _read("published_latency.csv", LATENCY_COLUMNS)


@pytest.fixture(scope="module")
def sources():
    return {s["source_id"]: s for s in _read("latency_sources.csv", SOURCE_COLUMNS)}


@pytest.fixture(scope="module")
def computers():
    with open(DATA / "computers.toml", "rb") as fh:
        return tomllib.load(fh)["computers"]


def test_every_row_has_allowed_values_and_a_known_source(rows, sources):
    assert len({r["row_id"] for r in rows}) == len(rows)
    for r in rows:
        where = f"row {r['row_id']}"
        assert r["source_id"] in sources, where
        assert r["computer"] in COMPUTERS, where
        assert r["runtime"] in RUNTIMES, where
        assert r["target"] in TARGETS, where
        assert r["precision"] in PRECISIONS, where
        assert r["network"] in NETWORKS, where
        assert int(r["input"]) >= 32, where
        assert 0.1 < float(r["latency_ms"]) < 60_000, where
        assert r["table"].strip() and r["row"].strip(), where
        if r["cpu_clock_ghz"]:                  # the source states another clock: say it
            assert 0.1 < float(r["cpu_clock_ghz"]) < 10 and "GHz" in r["notes"] + r["table"], where
        if r["threads"]:                        # not the runtime's default: say why
            assert r["target"] == "cpu" and int(r["threads"]) >= 1 and "thread" in r["notes"], where
        if r["runtime"] == "edgetpu":
            assert (r["target"], r["precision"]) == ("npu", "int8"), where
        if r["runtime"] == "tensorrt":
            assert r["target"] == "gpu", where
    keys = Counter((r["source_id"], r["computer"], r["runtime"], r["target"], r["precision"], r["network"],
                    r["input"]) for r in rows)
    assert max(keys.values()) == 1, [k for k, n in keys.items() if n > 1]


def test_sources_each_have_a_half_and_distinct_ids(sources, rows):
    assert {s["half"] for s in sources.values()} == {"tuning", "heldout"}
    for s in sources.values():
        assert s["document"].strip() and s["publisher"].strip() and s["where"].strip(), s["source_id"]
        assert 1990 < int(s["year"]) < 2100, s["source_id"]
    used = {r["source_id"] for r in rows}
    assert len(used) >= 8
    assert len({sources[s]["publisher"] for s in used}) >= 8


def test_table_size_and_coverage(rows, sources):
    assert len(rows) >= 80
    by_computer = defaultdict(list)
    for r in rows:
        by_computer[r["computer"]].append(r)
    assert len(by_computer) >= 6
    for name, rs in by_computer.items():
        if name != "coral-dev-board":  # the Edge TPU runs int8 TFLite models only
            assert len({r["runtime"] for r in rs}) >= 2, name
            assert len({r["precision"] for r in rs}) >= 2, name
    nets = {r["network"] for r in rows}
    assert nets & CLASSIFIERS and nets & DETECTORS
    halves = Counter(sources[r["source_id"]]["half"] for r in rows)
    assert halves["tuning"] >= 40 and halves["heldout"] >= 40
    heldout = Counter(r["computer"] for r in rows if sources[r["source_id"]]["half"] == "heldout")
    assert sum(n >= 8 for n in heldout.values()) >= 6, heldout


def _figures(table, path=""):
    """(dotted key, value, source) for every number in a datasheet table."""
    for key, value in table.items():
        if isinstance(value, dict):
            yield from _figures(value, f"{path}{key}.")
        elif (isinstance(value, (int, float)) and not isinstance(value, bool)) or key in ("runtimes", "core_type",
                                                                                          "arch", "isa", "kind"):
            yield f"{path}{key}", value, table.get(f"{key}_source", "")


def test_every_datasheet_figure_has_a_source(computers):
    assert set(computers) == COMPUTERS
    for name, sheet in computers.items():
        figures = list(_figures(sheet))
        assert len(figures) >= 5, name
        for key, _value, source in figures:
            assert isinstance(source, str) and source.strip(), f"{name}.{key} has no source"
        assert set(sheet["runtimes"]) <= RUNTIMES, name
        assert {"cpu", "gpu", "npu"} & set(sheet), name


def test_rows_only_use_runtimes_the_computer_runs(rows, computers):
    for r in rows:
        assert r["runtime"] in computers[r["computer"]]["runtimes"], r["row_id"]
        assert r["target"] == "cpu" or r["target"] in computers[r["computer"]], r["row_id"]


def test_published_energy_figures(sources, computers):
    energy = _read("energy_published.csv", ENERGY_COLUMNS)
    assert energy
    for e in energy:
        assert e["source_id"] in sources, e["energy_id"]
        assert e["computer"] in computers and e["runtime"] in RUNTIMES, e["energy_id"]
        assert e["precision"] in PRECISIONS and e["network"] in NETWORKS, e["energy_id"]
        assert float(e["latency_ms"]) > 0, e["energy_id"]
        assert e["power_w"] or e["energy_j"], e["energy_id"]
        for col in ("power_w", "idle_w", "energy_j"):
            assert not e[col] or float(e[col]) > 0, (e["energy_id"], col)
        assert e["measured_at"].strip(), e["energy_id"]


def test_sources_added_later_take_their_half_from_the_digest_of_their_id(sources):
    """Sources added after the first split are halved by rule, not by choice: tuning when the
    SHA-256 of the source id is even, held out when odd (decided before any prediction)."""
    import hashlib
    assert {s["added"] for s in sources.values()} <= {"2026-11", "2026-11-27", "2026-11-28",
                                                     "2026-12-06"}
    later = [s for s in sources.values() if s["added"] != "2026-11"]
    assert later
    for s in later:
        even = int(hashlib.sha256(s["source_id"].encode()).hexdigest(), 16) % 2 == 0
        assert s["half"] == ("tuning" if even else "heldout"), s["source_id"]
