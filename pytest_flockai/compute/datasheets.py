"""Reading the computers' datasheets into ``Device`` profiles.

``compute/data/computers.toml`` holds one table per computer (sources next to every
figure). Until that file is present, ``PLACEHOLDER`` below stands in: the same
schema, figures from the makers' datasheets as cited in each entry.

Schema of one computer (``[name]``): ``idle_w``, ``busy_w`` (board input, W),
``memory_mb``, ``bandwidth_gbs`` (DRAM peak), ``mode`` (power mode), ``runtimes``
(``"runtime/target"`` strings, first = default), ``macs_per_s`` and ``overhead_s``
(the MAC-count rule, kept for models known only by their MAC count), ``source``,
and ``units``: a list of {``kind``, ``cores``, ``clock_ghz``, and either
``macs_per_cycle`` = {precision: MACs per cycle per core} or ``peak_tmacs`` =
{precision: peak tera-MAC/s of the unit}}.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

from ..errors import ConfigError
from .devices import Device, Unit

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
                       "source": "Raspberry Pi 5 product brief"},
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
                               "source": "NVIDIA Jetson Orin Nano Super developer kit datasheet"},
    # Orin NX 16 GB, 25 W: 1024 CUDA + 32 tensor cores at 918 MHz, 8x A78AE 2 GHz, 102 GB/s.
    "jetson-orin-nx-16gb": {"idle_w": 4.0, "busy_w": 25.0, "memory_mb": 16384,
                            "bandwidth_gbs": 102.4, "mode": "25W", "runtimes": _JETSON,
                            "macs_per_s": 6e11, "overhead_s": 0.002,
                            "units": [{"kind": "gpu", "cores": 1, "clock_ghz": 0.918,
                                       "peak_tmacs": {"fp16": 7.5, "int8": 15.0, "fp32": 0.94}},
                                      _cpu(8, 2.0, 8, 32, 16)],
                            "source": "NVIDIA Jetson Orin NX series datasheet"},
    # Coral Dev Board: Edge TPU 4 TOPS int8 (2 TMAC/s), NXP i.MX 8M 4x Cortex-A53 1.5 GHz,
    # LPDDR4 1 GB (12.8 GB/s).
    "coral-dev-board": {"idle_w": 2.5, "busy_w": 4.5, "memory_mb": 1024, "bandwidth_gbs": 12.8,
                        "runtimes": ["edgetpu/npu", "tflite/cpu", "onnxruntime/cpu"],
                        "macs_per_s": 2e9, "overhead_s": 0.003,
                        "units": [{"kind": "npu", "cores": 1, "clock_ghz": 0.5,
                                   "peak_tmacs": {"int8": 2.0}}, _cpu(4, 1.5, 2, 4)],
                        "source": "Coral Dev Board datasheet; Edge TPU performance benchmarks"},
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
    return Unit(kind, cores, ghz, tuple((p, peak[p]) for p in order), str(u.get("name", "")))


def from_table(name: str, t: dict) -> Device:
    """A ``Device`` from one datasheet table (the schema in the module docstring)."""
    where = f"computer {name!r}"
    try:
        units = tuple(_unit(u, where) for u in t.get("units", ()))
        return Device(name, idle_w=float(t["idle_w"]), active_w=float(t["busy_w"]),
                      macs_per_s=float(t["macs_per_s"]), overhead_s=float(t["overhead_s"]),
                      memory_mb=float(t["memory_mb"]), source=str(t.get("source", "")),
                      units=units, bandwidth_gbs=float(t.get("bandwidth_gbs", 0.0)),
                      deployments=tuple(t.get("runtimes", ())), mode=str(t.get("mode", "")))
    except KeyError as e:
        raise ConfigError(f"{where}: missing field {e.args[0]!r}") from None


def load_devices() -> dict[str, Device]:
    """The profiles: ``computers.toml`` when present, else the placeholders."""
    tables = PLACEHOLDER
    if COMPUTERS.is_file():
        with COMPUTERS.open("rb") as fh:
            tables = tomllib.load(fh)
    return {n: from_table(n, t) for n, t in tables.items()}


__all__ = ["COMPUTERS", "PLACEHOLDER", "from_table", "load_devices"]
