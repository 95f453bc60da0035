"""``flockai profile-device``: time models on this computer and write a profile.

    flockai profile-device MODEL.onnx [MODEL2.onnx ...] --runtime onnxruntime|opencv-dnn|openvino
        [--target cpu|gpu] [--threads N] [--runs N] [--warmup N] [--input-shape 1x3x640x640]
        [--power-csv FILE [--idle-w W]] [--jetson-rails] [--name NAME] --out profile.json
    flockai profile-device MODEL.tflite|MODEL.param ... --runtime tflite|edgetpu|ncnn
        [--onnx MODEL.onnx ...] ...

Each model runs ``warmup`` times untimed, then ``runs`` times timed one by one
(``time.perf_counter`` around the runtime's call, batch 1, a fixed seeded input). The
profile records every timed latency, the runtime and its version, the threads, the
host's facts (CPU, cores, board model, memory, OS), what the runtime reports it
computed with (``runtime.execution``: ONNX Runtime's providers; OpenVINO's device, threads
and precision, which it picks itself: a float graph timed in bf16 or f16 is recorded as
``fp16``) and, when given, the busy power. The runtimes are in ``timed``. Busy power:

- ``--power-csv``: a watt meter's log, a CSV with a power column (``power_w``, ``watts``
  or ``power``) and optionally ``time_s`` (Unix seconds). With times, busy power is the
  mean over the timed runs (widened by one meter period when no sample falls inside)
  and idle power the mean before the first warm-up; without,
  every row is busy and ``--idle-w`` gives idle.
- ``--jetson-rails``: the board's own INA3221 input rail (``VDD_IN`` on Orin,
  ``POM_5V_IN`` on Nano), sampled every 50 ms: 2 s idle first, then during the runs.

``pytest_flockai.compute.profile(path)`` loads the result.
"""

from __future__ import annotations

import csv
import glob
import json
import os
import platform
import threading
import time
import warnings
from pathlib import Path

import cv2
import numpy as np
import onnx
import onnxruntime as ort

from .._io import atomic_write
from ..errors import ConfigError
from .graph import analyze, half_weights, quantization
from .profile import RUNTIMES, SCHEMA, from_dict, model_format, model_sha256
from .timed import MEASURABLE, OV_PRECISION, onnx_input, runner, targets

#: the runtime a model file is timed with when ``--runtime`` is not given
BY_FORMAT = {"onnx": "onnxruntime", "tflite": "tflite", "ncnn": "ncnn"}


def add_parser(sub) -> None:
    p = sub.add_parser("profile-device", help="time models on this computer with its "
                                              "runtime and write a device profile")
    p.add_argument("models", type=Path, nargs="+", metavar="MODEL.onnx",
                   help="ONNX files (.tflite files for --runtime tflite or edgetpu, "
                        ".param files with their .bin for ncnn)")
    p.add_argument("--runtime", default=None, help=f"one of {', '.join(MEASURABLE)} (default: "
                                                   f"onnxruntime for .onnx files, tflite for "
                                                   f".tflite, ncnn for .param)")
    p.add_argument("--target", default=None, help="cpu (default), gpu (onnxruntime's CUDA provider, "
                                                   "OpenVINO's GPU device) or npu (edgetpu)")
    p.add_argument("--threads", type=int, default=None, help="intra-op threads (runtime "
                                                             "default when absent)")
    p.add_argument("--runs", type=int, default=50, help="timed runs per model (default 50)")
    p.add_argument("--warmup", type=int, default=5, help="untimed runs first (default 5)")
    p.add_argument("--input-shape", default=None, help="the models' input shape, e.g. "
                                                       "1x3x640x640: it fills the dims a "
                                                       "model leaves open (fixed ones stay)")
    p.add_argument("--power-csv", type=Path, default=None, help="a watt meter's CSV log")
    p.add_argument("--idle-w", type=float, default=None, help="idle power (W) for --power-csv "
                                                              "without times")
    p.add_argument("--jetson-rails", action="store_true", help="read the Jetson's input rail")
    p.add_argument("--name", default=None, help="the computer's name (default: board model "
                                                "or host machine)")
    p.add_argument("--seed", type=int, default=0, help="seed of the input tensor")
    p.add_argument("--onnx", type=Path, action="append", default=None, metavar="MODEL.onnx",
                   help="for .tflite and ncnn models: the ONNX file each stands for, once "
                        "per model in order (a task flying that ONNX file then draws these "
                        "latencies; ncnn takes its input shape from it)")
    p.add_argument("--out", type=Path, required=True, help="the profile JSON to write")


def run_cli(a) -> int:
    doc = measure(a.models, runtime=a.runtime, target=a.target, threads=a.threads, runs=a.runs,
                  warmup=a.warmup, input_shape=a.input_shape, power_csv=a.power_csv,
                  idle_w=a.idle_w, jetson_rails=a.jetson_rails, name=a.name, seed=a.seed,
                  stands_for=a.onnx)
    write(doc, a.out)
    for m in doc["models"]:
        lat = np.asarray(m["latency_s"]) * 1e3
        print(f"flockai profile-device: {m['name']}: p50 {np.percentile(lat, 50):.3f} ms, "
              f"p95 {np.percentile(lat, 95):.3f} ms ({len(lat)} runs, {doc['runtime']['name']} "
              f"{doc['runtime']['version']})")
    print(f"flockai profile-device: wrote {a.out}")
    return 0


def write(doc: dict, path) -> None:
    """Check ``doc`` as ``profile()`` would, then write it atomically."""
    from_dict(doc, "profile to write")
    atomic_write(path, lambda fh: fh.write(json.dumps(doc, indent=1) + "\n"))


def _stands_for(models, onnx_paths) -> list:
    """One ONNX file (or None) per model; ConfigError unless ``--onnx`` is given once per
    model, each an ONNX file, and only for models that are not ONNX themselves."""
    if not onnx_paths:
        return [None] * len(models)
    if len(onnx_paths) != len(models):
        raise ConfigError(f"--onnx given {len(onnx_paths)} time(s) for {len(models)} model(s); "
                          f"expected once per model, in order")
    for m, o in zip(models, onnx_paths):
        if model_format(m) == "onnx":
            raise ConfigError(f"--onnx = {str(o)!r} is not allowed for {str(m)!r}, an ONNX "
                              f"model itself; --onnx names the ONNX file a .tflite or ncnn "
                              f"model stands for")
        if not os.path.isfile(o) or model_format(o) != "onnx":
            raise ConfigError(f"--onnx = {str(o)!r} is not allowed; expected an existing "
                              f".onnx file")
    return list(onnx_paths)


def _same_input(path, shape, onnx_path) -> None:
    """The ONNX file a .tflite or ncnn model stands for takes as many input values (NHWC
    and NCHW hold the same count); ConfigError where its input's dims are fixed and differ."""
    dims = onnx_input(onnx_path)[1]
    if None not in dims and int(np.prod(dims)) != int(np.prod(shape)):
        raise ConfigError(f"--onnx = {str(onnx_path)!r} is not allowed for {str(path)!r}: its "
                          f"input {'x'.join(map(str, dims))} and the timed model's input "
                          f"{'x'.join(map(str, shape))} differ in size, so they are not one "
                          f"network at one input size")


def _parse_shape(text):
    if text is None:
        return None
    try:
        dims = tuple(int(d) for d in str(text).lower().split("x"))
        if not dims or min(dims) < 1:
            raise ValueError
        return dims
    except ValueError:
        raise ConfigError(f"--input-shape = {text!r} is not allowed; expected dims >= 1 joined "
                          f"by x, e.g. 1x3x640x640") from None


def _check_int(name, value, low):
    if isinstance(value, bool) or not isinstance(value, int) or value < low:
        raise ConfigError(f"--{name} = {value!r} is not allowed; expected a whole number >= {low}")


def measure(models, *, runtime=None, target=None, threads=None, runs=50, warmup=5,
            input_shape=None, power_csv=None, idle_w=None, jetson_rails=False, name=None,
            seed=0, stands_for=None) -> dict:
    """Time each model and return the profile document (``write`` saves it).
    ``stands_for``: for ``.tflite`` and ncnn models, the ONNX file each stands for: the
    profile identifies the model by that file's SHA-256 (and counts its MACs), so a task
    flying it draws these latencies; the timed file is kept under ``file``. ``runtime``
    None: the first model's format's (``BY_FORMAT``)."""
    if runtime is None:
        runtime = BY_FORMAT[model_format(models[0])] if models else "onnxruntime"
    if runtime not in MEASURABLE:
        where = "known but not measurable here" if runtime in RUNTIMES else "unknown"
        raise ConfigError(f"--runtime = {runtime!r} is not allowed ({where}); profile-device "
                          f"measures with: {', '.join(MEASURABLE)}")
    if target is None:
        target = targets(runtime)[0]
    if target not in targets(runtime):
        raise ConfigError(f"--target = {target!r} is not allowed with --runtime {runtime}; "
                          f"allowed: {list(targets(runtime))}")
    _check_int("runs", runs, 1)
    _check_int("warmup", warmup, 0)
    if threads is not None:
        _check_int("threads", threads, 1)
    if idle_w is not None and not (np.isfinite(idle_w) and idle_w >= 0):
        raise ConfigError(f"--idle-w = {idle_w!r} is not allowed; expected watts >= 0")
    if power_csv is not None and jetson_rails:
        raise ConfigError("--power-csv and --jetson-rails are not allowed together; give one")
    shape = _parse_shape(input_shape)
    stands_for = _stands_for(models, stands_for)
    rails = _Rails() if jetson_rails else None
    t_start = time.time()
    if rails is not None:
        rails.start()
        time.sleep(2.0)
        rails.mark_busy()
    out_models: list = []
    version = ""
    execution: dict = {}
    try:
        for path, onnx_path in zip(models, stands_for):
            ident = onnx_path or path
            sha = model_sha256(ident)
            mshape = shape
            if mshape is None and onnx_path is not None and model_format(path) == "ncnn":
                dims = onnx_input(onnx_path)[1]     # ncnn's files do not hold the input's
                mshape = tuple(dims) if None not in dims else None
            r = runner(path, runtime, target, threads, mshape, seed)
            if onnx_path is not None:
                _same_input(path, r.input_shape, onnx_path)
            run, feed_shape, version = r.run, r.input_shape, r.version
            execution = execution or r.execution        # the first model's, as its precision
            for _ in range(warmup):
                run()
            t_busy = time.time()
            lat = []
            for _ in range(runs):
                t0 = time.perf_counter()
                run()
                lat.append(time.perf_counter() - t0)
            entry = {"name": Path(ident).stem, "path": os.fspath(ident), "sha256": sha,
                     "input_shape": list(feed_shape), "warmup": warmup, "runs": runs,
                     "macs": _macs(ident, feed_shape) if model_format(ident) == "onnx"
                     else None, "latency_s": lat, "t_busy": [t_busy, time.time()]}
            if onnx_path is not None or model_format(path) != "onnx":
                entry["file"] = {"path": os.fspath(path), "format": model_format(path),
                                 "sha256": model_sha256(path)}
            out_models.append(entry)
    finally:
        power = rails.stop() if rails is not None else None
    if power_csv is not None:
        power = _power_from_csv(power_csv, t_start, [m["t_busy"] for m in out_models], idle_w)
    for m in out_models:
        del m["t_busy"]
    host = host_facts()
    precision = (_precision(models[0]) if model_format(models[0]) == "onnx"
                 else execution["precision"])
    if precision == "fp32":     # the runtime's own choice (OpenVINO: bf16 or f16 on some CPUs)
        precision = OV_PRECISION.get(str(execution.get("precision", "f32")), precision)
    libraries = {"onnxruntime": ort.__version__, "opencv": cv2.__version__,
                 "onnx": onnx.__version__, "numpy": np.__version__}
    if runtime == "openvino":
        libraries["openvino"] = version
    elif runtime in ("tflite", "edgetpu"):
        libraries[execution["package"]] = version
    elif runtime == "ncnn":
        libraries["ncnn"] = version
    return {"schema": SCHEMA, "name": name or host.get("board") or host["machine"],
            "created": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
            "runtime": {"name": runtime, "version": version, "target": target,
                        "precision": precision, "threads": threads, "execution": execution,
                        "libraries": libraries},
            "host": host, "power": power, "models": out_models}


def _macs(path, shape):
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return int(analyze(path, tuple(shape), allow_uncounted=True).macs)
    except Exception:  # noqa: BLE001 (the MAC count is a convenience, timing is the point)
        return None


def _precision(path) -> str:
    """The precision an ONNX graph computes in, as ``predict_latency`` reads it: int8 for a
    quantized graph (``quantization``), fp16 for fp16 weights (``half_weights``)."""
    g = onnx.load(os.fspath(path), load_external_data=False).graph
    return "int8" if quantization(g) else "fp16" if half_weights(g) else "fp32"


def host_facts() -> dict:
    """What this computer is: OS, CPU, cores, board model, memory."""
    facts = {"machine": platform.machine(), "system": platform.system(),
             "release": platform.release(), "python": platform.python_version(),
             "cpu_count": os.cpu_count()}
    if hasattr(os, "sched_getaffinity"):
        facts["cpus_usable"] = len(os.sched_getaffinity(0))
    for path, key, pick in (("/proc/cpuinfo", "cpu", ("model name", "Model", "Hardware")),
                            ("/proc/meminfo", "memory", ("MemTotal",))):
        try:
            with open(path, encoding="utf-8", errors="replace") as fh:
                for line in fh:
                    k, _, v = line.partition(":")
                    if k.strip() in pick:
                        facts[key] = v.strip()
                        break
        except OSError:
            pass
    for path, key in (("/proc/device-tree/model", "board"), ("/etc/nv_tegra_release", "l4t"),
                      ("/sys/devices/system/cpu/cpu0/cpufreq/cpuinfo_max_freq", "cpu_max_khz")):
        try:
            facts[key] = Path(path).read_text(errors="replace").strip("\x00\n ").splitlines()[0]
        except (OSError, IndexError):
            pass
    return facts


def _power_from_csv(path, t_start, windows, idle_w) -> dict:
    where = f"--power-csv {str(path)!r}"
    try:
        with open(path, encoding="utf-8", newline="") as fh:
            rows = list(csv.DictReader(fh))
    except (OSError, UnicodeDecodeError, csv.Error) as e:
        raise ConfigError(f"{where} cannot be read: {e}") from None
    cols = {c.strip().lower(): c for c in (rows[0].keys() if rows else [])}
    pcol = next((cols[c] for c in ("power_w", "watts", "power") if c in cols), None)
    if pcol is None:
        raise ConfigError(f"{where}: columns {list(cols)} have no power column; expected "
                          f"power_w (or watts, power) and optionally time_s")
    try:
        watts = np.array([float(r[pcol]) for r in rows])
        times = np.array([float(r[cols["time_s"]]) for r in rows]) if "time_s" in cols else None
    except (TypeError, ValueError) as e:
        raise ConfigError(f"{where}: a value is not a number ({e})") from None
    if not np.all(np.isfinite(watts)) or np.any(watts < 0):
        raise ConfigError(f"{where}: power values must be watts >= 0")
    busy, idle = watts, None
    if times is not None:
        # a run shorter than the meter's period: widen each window by one period
        period = float(np.median(np.diff(np.sort(times)))) if len(times) > 1 else 0.0
        in_run = np.zeros(len(times), bool)
        for pad in (0.0, period):
            for t0, t1 in windows:
                in_run |= (times >= t0 - pad) & (times <= t1 + pad)
            if in_run.any():
                break
        busy, before = watts[in_run], watts[times < t_start]
        idle = float(before.mean()) if before.size else None
        if not busy.size:
            raise ConfigError(f"{where}: no sample falls in the timed runs "
                              f"({windows[0][0]:.0f} .. {windows[-1][1]:.0f} Unix s)")
    return {"source": f"watt meter CSV {Path(path).name}", "busy_w": float(busy.mean()),
            "idle_w": idle if idle is not None else idle_w, "samples": int(busy.size)}


class _Rails:
    """Samples the Jetson's INA3221 input rail in a thread (W)."""

    def __init__(self, root="/sys"):
        self.read = _rail_reader(root)
        self.idle: list[float] = []
        self.busy: list[float] = []
        self._into = self.idle
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, daemon=True)

    def _loop(self):
        while not self._stop.wait(0.05):
            self._into.append(self.read())

    def start(self):
        self._thread.start()

    def mark_busy(self):
        self._into = self.busy

    def stop(self) -> dict:
        self._stop.set()
        self._thread.join()
        return {"source": "Jetson INA3221 input rail", "samples": len(self.busy),
                "busy_w": float(np.mean(self.busy)) if self.busy else None,
                "idle_w": float(np.mean(self.idle)) if self.idle else None}


def _rail_reader(root):
    for label in glob.glob(f"{root}/bus/i2c/drivers/ina3221/*/hwmon/hwmon*/in*_label"):
        if Path(label).read_text().strip() == "VDD_IN":            # Orin: mV x mA
            base = label[:-len("_label")]
            cur = base.replace("/in", "/curr")

            def orin(v=base + "_input", c=cur + "_input"):
                return float(Path(v).read_text()) * float(Path(c).read_text()) / 1e6
            return orin
    for name in glob.glob(f"{root}/bus/i2c/drivers/ina3221x/*/iio:device*/rail_name_*"):
        if Path(name).read_text().strip() == "POM_5V_IN":          # Nano: mW
            k = name.rsplit("_", 1)[1]
            p = str(Path(name).parent / f"in_power{k}_input")
            return lambda: float(Path(p).read_text()) / 1e3
    raise ConfigError(f"--jetson-rails: no INA3221 input rail (VDD_IN or POM_5V_IN) under "
                      f"{root}; this computer is not a Jetson: give --power-csv instead")


__all__ = ["BY_FORMAT", "add_parser", "host_facts", "measure", "run_cli", "write"]
