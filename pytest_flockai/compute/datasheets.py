"""Reading the computers' datasheets into ``Device`` profiles.

``compute/data/computers.toml`` holds one table per computer under ``[computers.NAME]``
(a ``<field>_source`` next to every figure): ``memory_mb``, ``memory_bandwidth_gbs``
(``memory_bandwidth_stream_gbs`` where a STREAM figure is published), ``runtimes``,
``[.cpu]`` (``cores``, ``clock_ghz``, ``fp32/fp16_flop_per_cycle_per_core``,
``int8_ops_per_cycle_per_core``), ``[.gpu]`` (``clock_ghz``, ``fp32_tflops``,
``fp16_tflops`` / ``fp16_tensor_tflops``, ``int8_tops``), ``[.npu]`` (``int8_tops``),
``[.power]`` (``idle_w``, ``busy_w``: measured where published, else an estimate that its
source calls one) and ``[.mac_rule]`` (``macs_per_s``, ``overhead_s``: the MAC-count rule
for a model known only by its MAC count, an estimate). ``from_datasheet`` reads it:

- peak MACs = FLOP (or int8 ops) / 2; a precision without a figure is one the unit cannot
  run (a CPU without ``fp16_flop...``: no fp16 arithmetic, e.g. Cortex-A57/A72), except
  int8 on a CPU without ``int8_ops...``: twice its fp32 rate (NEON 16-bit-widening
  multiply-accumulates, no dot product); a GPU's fp16 without a figure: half of
  ``tensor_tflops_sparse`` (NVIDIA's sparse figures are twice the dense ones);
- a unit without a clock or a peak is left out (no deployment can use it);
- each runtime runs on the units ``TARGET_ORDER`` lists for it that the computer has;
- a missing ``memory_mb``, ``[.power]`` figure or ``[.mac_rule]`` figure is a
  ``ConfigError`` naming the computer and the field.
"""

from __future__ import annotations

import tomllib
from dataclasses import replace
from pathlib import Path

from ..errors import ConfigError
from ._device import Device, Unit

DATA = Path(__file__).with_name("data")
COMPUTERS = DATA / "computers.toml"

#: the units each runtime runs on, in order of preference (the first present is its default)
TARGET_ORDER = {"tensorrt": ("gpu",), "edgetpu": ("npu",), "pytorch": ("gpu", "cpu"),
                "onnxruntime": ("gpu", "cpu"), "opencv-dnn": ("cpu", "gpu"),
                "ncnn": ("cpu", "gpu"), "tflite": ("cpu",), "openvino": ("cpu",)}


def _peaks(kind: str, u: dict) -> dict:
    """{precision: peak MAC/s of the whole unit} from one unit's table."""
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


def _unit(kind: str, u: dict, peaks: dict) -> Unit:
    order = [p for p in ("fp32", "fp16", "int8") if p in peaks]
    if kind != "cpu":                      # accelerators default to their fastest precision
        order = [p for p in ("fp16", "int8", "fp32") if p in peaks]
        if kind == "npu":
            order = sorted(order, key=lambda p: p != "int8")
    return Unit(kind, int(u.get("cores", 1)) if kind == "cpu" else 1,
                float(u.get("clock_ghz", 0.0)), tuple((p, float(peaks[p])) for p in order),
                str(u.get("core_type", u.get("arch", u.get("kind", "")))),
                int(u.get("tensor_cores", 0)))


def _need(t: dict, name: str, table: str, key: str) -> float:
    sub = t.get(table, {}) if table else t
    if not isinstance(sub, dict) or key not in sub:
        where = f"[computers.{name}.{table}]" if table else f"[computers.{name}]"
        raise ConfigError(f"{COMPUTERS.name}: {where} {key} is missing; every computer needs "
                          f"memory_mb, power.idle_w, power.busy_w, mac_rule.macs_per_s and "
                          f"mac_rule.overhead_s (each with its _source)")
    return float(sub[key])


def from_datasheet(name: str, t: dict) -> Device:
    """A ``Device`` from one ``[computers.NAME]`` table of ``computers.toml``."""
    units = []
    for kind in ("gpu", "npu", "cpu"):
        u = t.get(kind)
        if isinstance(u, dict):
            peaks = _peaks(kind, u)
            if peaks:
                unit = _unit(kind, u, peaks)
                if kind == "npu" and u.get("on_chip_memory_mb") and t.get("edgetpu_link_gbs"):
                    unit = replace(unit, cache_mb=float(u["on_chip_memory_mb"]),
                                   link_gbs=float(t["edgetpu_link_gbs"]))
                units.append(unit)
    have = {u.kind for u in units}
    deps = tuple(f"{r}/{k}" for r in t.get("runtimes", ()) for k in TARGET_ORDER.get(r, ())
                 if k in have)
    sources = tuple((k, str(v)) for k, v in _flat(t) if k.endswith("_source"))
    est = [k.removesuffix("_source") for k, v in sources if v.startswith("estimate")]
    src = f"{name}: compute/data/computers.toml" + (
        f" (estimates, not measurements: {', '.join(est)})" if est else "")
    return Device(name, idle_w=_need(t, name, "power", "idle_w"),
                  active_w=_need(t, name, "power", "busy_w"),
                  macs_per_s=_need(t, name, "mac_rule", "macs_per_s"),
                  overhead_s=_need(t, name, "mac_rule", "overhead_s"),
                  memory_mb=_need(t, name, "", "memory_mb"),
                  source=src, units=tuple(units),
                  bandwidth_gbs=float(t.get("memory_bandwidth_gbs", 0.0)),
                  stream_gbs=float(t.get("memory_bandwidth_stream_gbs", 0.0)),
                  deployments=deps, mode=str(t.get("name", "")), sources=sources)


def _flat(t: dict, prefix: str = ""):
    for k, v in t.items():
        if isinstance(v, dict):
            yield from _flat(v, f"{prefix}{k}.")
        else:
            yield f"{prefix}{k}", v


def load_devices(path: Path = COMPUTERS) -> dict[str, Device]:
    """The profiles of ``computers.toml``."""
    with Path(path).open("rb") as fh:
        data = tomllib.load(fh)
    return {n: from_datasheet(n, t) for n, t in data.get("computers", {}).items()}


__all__ = ["COMPUTERS", "TARGET_ORDER", "from_datasheet", "load_devices"]
