"""Device profiles: active/idle power and effective ML throughput.

Power figures are measured at the board's input; sources next to each number.
``macs_per_s`` is an effective multiply-accumulate rate for CNN inference with
a common runtime (not peak): see each source.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

from ..errors import ConfigError, close_matches


@dataclass(frozen=True)
class Device:
    """A computer a task runs on: idle and active power (W, at the board's input),
    effective ML throughput (MAC/s), per-inference overhead (s) and memory (MB)."""

    name: str
    idle_w: float
    active_w: float
    macs_per_s: float
    overhead_s: float
    memory_mb: float
    source: str

    def to_dict(self) -> dict:
        """The fields as a JSON-ready dict."""
        return asdict(self)


DEVICES: dict[str, Device] = {d.name: d for d in (
    # Raspberry Pi 4 B: idle 2.2-3.0 W, high CPU + Wi-Fi 5.1-6.3 W, measured at the
    # USB input (Raspberry Pi Foundation / Tom's Hardware / pidramble.com power benches;
    # the FlockAI paper, section 4.4, uses ~8 W active).
    # Effective ~1.5 GMAC/s for float32 CNNs on 4 Cortex-A72 cores with ONNX
    # Runtime (MobileNetV2 300 MMAC in ~0.2 s, public RPi 4 ORT benchmarks).
    Device("raspberry-pi-4", idle_w=2.7, active_w=6.0, macs_per_s=1.5e9, overhead_s=0.01,
           memory_mb=4096, source="RPi 4 USB-input power benches; public RPi 4 ONNX Runtime benchmarks"),
    # Jetson Nano: nvpmodel 5 W and 10 W (MAXN) modes (NVIDIA Jetson Nano datasheet).
    # Effective GPU throughput ~25 / 50 GMAC/s for small CNNs with TensorRT FP16
    # (NVIDIA "Jetson Nano benchmarks": MobileNet-v2 ~ 60-120 fps at 300 MMAC).
    Device("jetson-nano-5w", idle_w=1.25, active_w=5.0, macs_per_s=2.5e10, overhead_s=0.005,
           memory_mb=4096, source="NVIDIA Jetson Nano datasheet (5 W mode)"),
    Device("jetson-nano-10w", idle_w=1.25, active_w=10.0, macs_per_s=5.0e10, overhead_s=0.004,
           memory_mb=4096, source="NVIDIA Jetson Nano datasheet (10 W MAXN mode)"),
    # Jetson Orin Nano 8 GB: 7 / 15 / 25 W modes (NVIDIA datasheet); 15 W mode taken.
    Device("jetson-orin-nano", idle_w=3.0, active_w=15.0, macs_per_s=4.0e11, overhead_s=0.002,
           memory_mb=8192, source="NVIDIA Jetson Orin Nano 8 GB datasheet (15 W mode)"),
    # Ground station: a desktop GPU (e.g. RTX 3060 class, 170 W board power).
    Device("ground-gpu", idle_w=15.0, active_w=170.0, macs_per_s=5.0e12, overhead_s=0.002,
           memory_mb=12288, source="NVIDIA RTX 3060 specifications (170 W)"),
)}


def devices() -> list[str]:
    """Names of the known device profiles."""
    return sorted(DEVICES)


def device(name: str) -> Device:
    """The profile named ``name`` (``devices()`` lists them); ConfigError otherwise."""
    try:
        return DEVICES[name]
    except KeyError:
        raise ConfigError(f"unknown device {name!r}{close_matches(name, DEVICES)}; "
                          f"available: {', '.join(devices())}") from None
