"""Reading the computers' datasheets into ``Device`` profiles.

``compute/data/computers.toml`` holds one table per computer under ``[computers.NAME]``
(a ``<field>_source`` next to every figure): ``memory_mb``, ``memory_bandwidth_gbs``,
``runtimes``, ``[.cpu]`` (``cores``, ``clock_ghz``, ``fp32/fp16_flop_per_cycle_per_core``,
``int8_ops_per_cycle_per_core``), ``[.gpu]`` (``clock_ghz``, ``fp32_tflops``,
``fp16_tflops`` / ``fp16_tensor_tflops``, ``int8_tops``), ``[.npu]`` (``int8_tops``) and
``[.power]`` (``idle_w``, ``busy_w``). ``from_datasheet`` reads it, with these rules:

- peak MACs = FLOP (or int8 ops) / 2; a precision without a figure is one the unit cannot
  run (a CPU without ``fp16_flop...``: no fp16 arithmetic, e.g. Cortex-A57/A72), except
  int8 on a CPU without ``int8_ops...``: twice its fp32 rate (NEON 16-bit-widening
  multiply-accumulates, no dot product); a GPU's fp16 without a figure: half of
  ``tensor_tflops_sparse`` (NVIDIA's sparse figures are twice the dense ones);
- a unit without a clock or a peak is left out (no deployment can use it);
- each runtime runs on the units ``TARGET_ORDER`` lists for it that the computer has;
- power: ``[.power]``'s ``idle_w`` / ``busy_w`` when published; else the previous profile's
  figure (``PLACEHOLDER``, its source kept); the MAC-count rule (``macs_per_s``,
  ``overhead_s``) always from the previous profile.

``PLACEHOLDER`` also stands in entirely when ``computers.toml`` is absent.

Schema of one placeholder (``[name]``): ``idle_w``, ``busy_w`` (board input, W),
``memory_mb``, ``bandwidth_gbs`` (DRAM peak), ``mode`` (power mode), ``runtimes``
(``"runtime/target"`` strings, first = default), ``macs_per_s`` and ``overhead_s``
(the MAC-count rule, kept for models known only by their MAC count), ``source``,
and ``units``: a list of {``kind``, ``cores``, ``clock_ghz``, and either
``macs_per_cycle`` = {precision: MACs per cycle per core} or ``peak_tmacs`` =
{precision: peak tera-MAC/s of the unit}}.
"""

from __future__ import annotations

import tomllib
from dataclasses import replace
from pathlib import Path

from ..errors import ConfigError
from ._device import Device, Unit

DATA = Path(__file__).with_name("data")
COMPUTERS = DATA / "computers.toml"

_CPU_ONLY = ["onnxruntime/cpu", "tflite/cpu", "ncnn/cpu", "openvino/cpu", "opencv-dnn/cpu",
             "pytorch/cpu"]
_JETSON = ["tensorrt/gpu", "onnxruntime/gpu", "pytorch/gpu", "onnxruntime/cpu", "ncnn/cpu",
           "tflite/cpu", "opencv-dnn/cpu", "pytorch/cpu", "ncnn/gpu", "opencv-dnn/gpu", "openvino/cpu"]


def _cpu(cores, ghz, fp32, int8, fp16=None):
    mpc = {"fp32": fp32, "int8": int8, **({"fp16": fp16} if fp16 else {})}
    return {"kind": "cpu", "cores": cores, "clock_ghz": ghz, "macs_per_cycle": mpc}


# Placeholder datasheets (replaced by computers.toml). CPU MACs/cycle/core: NEON 128-bit
# FMA = 4 fp32 MACs per pipe (Arm Cortex-A72/A57/A53 software optimization guides: one
# 128-bit FP pipe pair; A76/A78: two 128-bit FMA pipes), int8 without SDOT = 2x fp32,
# with SDOT (Armv8.2: A76, A78AE) = 4x per pipe. GPU peaks from NVIDIA datasheets.
PLACEHOLDER: dict[str, dict] = {
    # Raspberry Pi 4 B: BCM2711, 4x Cortex-A72 1.5 GHz, LPDDR4-3200 32-bit (12.8 GB/s);
    # power: idle 2.7 W, CPU-busy ~6 W at the USB input (RPi 4 power benches).
    "raspberry-pi-4": {"idle_w": 2.7, "busy_w": 6.0, "memory_mb": 4096, "bandwidth_gbs": 12.8,
                       "runtimes": _CPU_ONLY, "macs_per_s": 1.5e9, "overhead_s": 0.01,
                       "units": [_cpu(4, 1.5, 4, 8)],
                       "source": "Raspberry Pi 4 B product brief; RPi 4 USB-input power benches"},
    # Raspberry Pi 5: BCM2712, 4x Cortex-A76 2.4 GHz, LPDDR4X-4267 32-bit (17 GB/s).
    "raspberry-pi-5": {"idle_w": 2.7, "busy_w": 7.5, "memory_mb": 8192, "bandwidth_gbs": 17.1,
                       "runtimes": _CPU_ONLY, "macs_per_s": 6e9, "overhead_s": 0.005,
                       "units": [_cpu(4, 2.4, 8, 32, 16)],
                       "source": "Raspberry Pi 5 product brief; power: an estimate, no published watt-meter figure"},
    # Jetson Nano 4 GB: 128 Maxwell CUDA cores (921 MHz at 10 W: 236 GFLOPS fp32, 472 fp16;
    # 640 MHz at 5 W), 4x Cortex-A57 1.43 GHz (2 cores 0.92 GHz at 5 W), 25.6 GB/s.
    "jetson-nano-5w": {"idle_w": 1.25, "busy_w": 5.0, "memory_mb": 4096, "bandwidth_gbs": 25.6,
                       "mode": "5W", "runtimes": _JETSON, "macs_per_s": 2.5e10,
                       "overhead_s": 0.005,
                       "units": [{"kind": "gpu", "cores": 1, "clock_ghz": 0.64,
                                  "peak_tmacs": {"fp16": 0.164, "fp32": 0.082}},
                                 _cpu(2, 0.92, 4, 8)],
                       "source": "NVIDIA Jetson Nano datasheet (5 W mode)"},
    "jetson-nano-10w": {"idle_w": 1.25, "busy_w": 10.0, "memory_mb": 4096, "bandwidth_gbs": 25.6,
                        "mode": "MAXN", "runtimes": _JETSON, "macs_per_s": 5e10,
                        "overhead_s": 0.004,
                        "units": [{"kind": "gpu", "cores": 1, "clock_ghz": 0.921,
                                   "peak_tmacs": {"fp16": 0.236, "fp32": 0.118}},
                                  _cpu(4, 1.43, 4, 8)],
                        "source": "NVIDIA Jetson Nano datasheet (10 W MAXN mode)"},
    # Jetson Orin Nano 8 GB, 15 W: 1024 Ampere CUDA cores + 32 tensor cores at 625 MHz
    # (20 dense int8 TOPS of 40 sparse), 6x Cortex-A78AE 1.5 GHz, 68 GB/s.
    "jetson-orin-nano": {"idle_w": 3.0, "busy_w": 15.0, "memory_mb": 8192, "bandwidth_gbs": 68,
                         "mode": "15W", "runtimes": _JETSON, "macs_per_s": 4e11,
                         "overhead_s": 0.002,
                         "units": [{"kind": "gpu", "cores": 1, "clock_ghz": 0.625,
                                    "peak_tmacs": {"fp16": 5.0, "int8": 10.0, "fp32": 0.64}},
                                   _cpu(6, 1.5, 8, 32, 16)],
                         "source": "NVIDIA Jetson Orin Nano 8 GB datasheet (15 W mode)"},
    # MAXN SUPER: GPU 1020 MHz (67 sparse int8 TOPS), CPU 1.7 GHz, 102 GB/s.
    "jetson-orin-nano-super": {"idle_w": 3.0, "busy_w": 25.0, "memory_mb": 8192,
                               "bandwidth_gbs": 102, "mode": "MAXN SUPER", "runtimes": _JETSON,
                               "macs_per_s": 6.5e11, "overhead_s": 0.002,
                               "units": [{"kind": "gpu", "cores": 1, "clock_ghz": 1.02,
                                          "peak_tmacs": {"fp16": 8.4, "int8": 16.8,
                                                         "fp32": 1.04}},
                                         _cpu(6, 1.7, 8, 32, 16)],
                               "source": "NVIDIA Jetson Orin Nano Super developer kit datasheet; power: an estimate, no published watt-meter figure"},
    # Orin NX 16 GB, 25 W: 1024 CUDA + 32 tensor cores at 918 MHz, 8x A78AE 2 GHz, 102 GB/s.
    "jetson-orin-nx-16gb": {"idle_w": 4.0, "busy_w": 25.0, "memory_mb": 16384,
                            "bandwidth_gbs": 102.4, "mode": "25W", "runtimes": _JETSON,
                            "macs_per_s": 6e11, "overhead_s": 0.002,
                            "units": [{"kind": "gpu", "cores": 1, "clock_ghz": 0.918,
                                       "peak_tmacs": {"fp16": 7.5, "int8": 15.0, "fp32": 0.94}},
                                      _cpu(8, 2.0, 8, 32, 16)],
                            "source": "NVIDIA Jetson Orin NX series datasheet; power: an estimate, no published watt-meter figure"},
    # Coral Dev Board: Edge TPU 4 TOPS int8 (2 TMAC/s), NXP i.MX 8M 4x Cortex-A53 1.5 GHz,
    # LPDDR4 1 GB (12.8 GB/s).
    "coral-dev-board": {"idle_w": 2.5, "busy_w": 4.5, "memory_mb": 1024, "bandwidth_gbs": 12.8,
                        "runtimes": ["edgetpu/npu", "tflite/cpu", "onnxruntime/cpu"],
                        "macs_per_s": 2e9, "overhead_s": 0.003,
                        "units": [{"kind": "npu", "cores": 1, "clock_ghz": 0.5,
                                   "peak_tmacs": {"int8": 2.0}}, _cpu(4, 1.5, 2, 4)],
                        "source": "Coral Dev Board datasheet; Edge TPU performance benchmarks; power: an estimate, no published watt-meter figure"},
    # Ground station: RTX 3060 (3584 CUDA cores, 1.78 GHz boost: 12.7 TFLOPS fp32,
    # 51 fp16 tensor TFLOPS, 102 int8 TOPS dense), 360 GB/s, 170 W board power.
    "ground-gpu": {"idle_w": 15.0, "busy_w": 170.0, "memory_mb": 12288, "bandwidth_gbs": 360,
                   "runtimes": ["tensorrt/gpu", "onnxruntime/gpu", "pytorch/gpu",
                                "onnxruntime/cpu", "openvino/cpu", "pytorch/cpu"],
                   "macs_per_s": 5e12, "overhead_s": 0.002,
                   "units": [{"kind": "gpu", "cores": 1, "clock_ghz": 1.78,
                              "peak_tmacs": {"fp16": 25.5, "int8": 51.0, "fp32": 6.35}},
                             _cpu(6, 3.5, 16, 32)],
                   "source": "NVIDIA RTX 3060 specifications (170 W)"},
}


def _unit(u: dict, where: str) -> Unit:
    kind = u.get("kind")
    if kind not in ("cpu", "gpu", "npu"):
        raise ConfigError(f"{where}: unit kind = {kind!r} is not allowed; allowed: cpu, gpu, npu")
    cores, ghz = int(u.get("cores", 1)), float(u.get("clock_ghz", 0.0))
    if "macs_per_cycle" in u:
        peak = {p: cores * ghz * 1e9 * float(v) for p, v in u["macs_per_cycle"].items()}
    elif "peak_tmacs" in u:
        peak = {p: float(v) * 1e12 for p, v in u["peak_tmacs"].items()}
    else:
        raise ConfigError(f"{where}: unit {kind!r} needs macs_per_cycle or peak_tmacs")
    order = [p for p in ("fp32", "fp16", "int8") if p in peak]
    if kind != "cpu":                      # accelerators default to their fastest precision
        order = [p for p in ("fp16", "int8", "fp32") if p in peak]
        if kind == "npu":
            order = sorted(order, key=lambda p: p != "int8")
    return Unit(kind, cores, ghz, tuple((p, peak[p]) for p in order), str(u.get("name", "")),
                int(u.get("tensor_cores", 0)))


def from_table(name: str, t: dict) -> Device:
    """A ``Device`` from one datasheet table (the schema in the module docstring)."""
    where = f"computer {name!r}"
    try:
        units = tuple(_unit(u, where) for u in t.get("units", ()))
        return Device(name, idle_w=float(t["idle_w"]), active_w=float(t["busy_w"]),
                      macs_per_s=float(t["macs_per_s"]), overhead_s=float(t["overhead_s"]),
                      memory_mb=float(t["memory_mb"]), source=str(t.get("source", "")),
                      units=units, bandwidth_gbs=float(t.get("bandwidth_gbs", 0.0)),
                      stream_gbs=float(t.get("stream_gbs", 0.0)),
                      deployments=tuple(t.get("runtimes", ())), mode=str(t.get("mode", "")))
    except KeyError as e:
        raise ConfigError(f"{where}: missing field {e.args[0]!r}") from None


#: the units each runtime runs on, in order of preference (the first present is its default)
TARGET_ORDER = {"tensorrt": ("gpu",), "edgetpu": ("npu",), "pytorch": ("gpu", "cpu"),
                "onnxruntime": ("gpu", "cpu"), "opencv-dnn": ("cpu", "gpu"),
                "ncnn": ("cpu", "gpu"), "tflite": ("cpu",), "openvino": ("cpu",)}


def _peaks(kind: str, u: dict) -> dict:
    if kind == "cpu":
        per = {p: u.get(f"{p}_flop_per_cycle_per_core") for p in ("fp32", "fp16")}
        per["int8"] = u.get("int8_ops_per_cycle_per_core")
        if per["int8"] is None and per["fp32"] is not None:
            per["int8"] = 2 * per["fp32"]
        n, ghz = u.get("cores"), u.get("clock_ghz")
        if not n or not ghz:
            return {}
        return {p: n * ghz * 1e9 * v / 2 for p, v in per.items() if v}
    fp16 = u.get("fp16_tensor_tflops", u.get("fp16_tflops"))
    if fp16 is None and u.get("tensor_tflops_sparse"):
        fp16 = u["tensor_tflops_sparse"] / 2
    tera = {"fp32": u.get("fp32_tflops"), "fp16": fp16, "int8": u.get("int8_tops")}
    return {p: v * 1e12 / 2 for p, v in tera.items() if v}


def from_datasheet(name: str, t: dict) -> Device:
    """A ``Device`` from one ``[computers.NAME]`` table of ``computers.toml``."""
    old = PLACEHOLDER.get(name, {})
    units = []
    for kind in ("gpu", "npu", "cpu"):
        u = t.get(kind)
        if not isinstance(u, dict):
            continue
        peaks = _peaks(kind, u)
        if peaks:
            units.append({"kind": kind, "cores": int(u.get("cores", 1)) if kind == "cpu" else 1,
                          "clock_ghz": float(u.get("clock_ghz", 0.0)),
                          "name": str(u.get("core_type", u.get("arch", u.get("kind", "")))),
                          "tensor_cores": int(u.get("tensor_cores", 0)),
                          "peak_tmacs": {p: v / 1e12 for p, v in peaks.items()}})
    have = {u["kind"] for u in units}
    deps = [f"{r}/{k}" for r in t.get("runtimes", ()) for k in TARGET_ORDER.get(r, ())
            if k in have]
    power = t.get("power", {})
    src = [f"{name}: compute/data/computers.toml"]
    for f, key in (("idle_w", "idle_w"), ("busy_w", "busy_w")):
        if key not in power:
            src.append(f"{f} from the previous profile ({old.get('source', 'none')})")
    idle, busy = power.get("idle_w", old.get("idle_w")), power.get("busy_w", old.get("busy_w"))
    table = {"idle_w": idle, "busy_w": busy,
             "memory_mb": t.get("memory_mb", old.get("memory_mb")),
             "bandwidth_gbs": t.get("memory_bandwidth_gbs", 0.0), "runtimes": deps,
             "stream_gbs": t.get("memory_bandwidth_stream_gbs", 0.0),
             "mode": str(t.get("name", "")), "macs_per_s": old.get("macs_per_s"),
             "overhead_s": old.get("overhead_s"), "units": units, "source": "; ".join(src)}
    dev = from_table(name, table)
    sources = tuple((k, str(v)) for k, v in _flat(t) if k.endswith("_source"))
    return replace(dev, sources=sources)


def _flat(t: dict, prefix: str = ""):
    for k, v in t.items():
        if isinstance(v, dict):
            yield from _flat(v, f"{prefix}{k}.")
        else:
            yield f"{prefix}{k}", v


def load_devices() -> dict[str, Device]:
    """The profiles: ``computers.toml`` when present, else the placeholders."""
    if not COMPUTERS.is_file():
        return {n: from_table(n, t) for n, t in PLACEHOLDER.items()}
    with COMPUTERS.open("rb") as fh:
        data = tomllib.load(fh)
    return {n: from_datasheet(n, t) for n, t in data.get("computers", {}).items()}


__all__ = ["COMPUTERS", "PLACEHOLDER", "TARGET_ORDER", "from_datasheet", "from_table",
           "load_devices"]
