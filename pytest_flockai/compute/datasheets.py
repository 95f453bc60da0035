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
- a GPU runs the CUDA runtimes (TensorRT, PyTorch, ONNX Runtime, OpenCV's DNN) only when
  its table gives ``cuda_cores`` (an NVIDIA GPU; ncnn's Vulkan runs on any), and an NPU runs
  ``edgetpu`` only when its ``kind`` is the Edge TPU;
- a missing ``memory_mb``, ``[.power]`` figure or ``[.mac_rule]`` figure is a
  ``ConfigError`` naming the computer and the field; so is a field the schema
  (``SCHEMA``) does not know, or a figure that is not a positive number.

``computer(source, name)`` reads a team's own datasheet (``compute.own``).
"""

from __future__ import annotations

import tomllib
from dataclasses import replace
from pathlib import Path

from ..errors import ConfigError, close_matches
from ._device import Device, Unit

DATA = Path(__file__).with_name("data")
COMPUTERS = DATA / "computers.toml"

#: the units each runtime runs on, in order of preference (the first present is its default)
TARGET_ORDER = {"tensorrt": ("gpu",), "edgetpu": ("npu",), "pytorch": ("gpu", "cpu"),
                "onnxruntime": ("gpu", "cpu"), "opencv-dnn": ("cpu", "gpu"),
                "ncnn": ("cpu", "gpu"), "tflite": ("cpu",), "openvino": ("cpu",)}


#: the runtimes a GPU runs only through CUDA (an NVIDIA GPU: ``cuda_cores`` in its table)
CUDA_RUNTIMES = ("tensorrt", "pytorch", "onnxruntime", "opencv-dnn")

#: the fields of a computer's table, per sub-table ("": the computer's own), each with its
#: type ("num": a number > 0, "int": a whole number > 0; "num0", "int0": 0 allowed too);
#: every field may have a
#: ``<field>_source`` next to it
SCHEMA: dict[str, dict[str, str]] = {
    "": {"name": "str", "memory_mb": "num", "memory_bandwidth_gbs": "num",
         "memory_bandwidth_stream_gbs": "num", "runtimes": "list", "edgetpu_link_gbs": "num",
         "mode_budget_w": "num"},
    "cpu": {"cores": "int", "clock_ghz": "num", "fp32_flop_per_cycle_per_core": "num",
            "fp16_flop_per_cycle_per_core": "num", "int8_ops_per_cycle_per_core": "num",
            "core_type": "str", "isa": "str"},
    "gpu": {"clock_ghz": "num", "fp32_tflops": "num", "fp16_tflops": "num",
            "fp16_tensor_tflops": "num", "int8_tops": "num", "int8_tops_sparse": "num",
            "tensor_tflops_sparse": "num", "module_ai_tops_sparse": "num", "cuda_cores": "int",
            "tensor_cores": "int0", "arch": "str"},
    "npu": {"int8_tops": "num", "on_chip_memory_mb": "num", "watts_per_tops": "num",
            "kind": "str"},
    "power": {"idle_w": "num0", "busy_w": "num", "typical_active_w": "num", "tpu_peak_w": "num"},
    "mac_rule": {"macs_per_s": "num", "overhead_s": "num"},
}


def check(name: str, t, where: str) -> None:
    """ConfigError naming the field, the value and what is allowed for anything in the table
    ``t`` of computer ``name`` the schema does not allow (``where``: the file, for the
    message)."""
    if not isinstance(t, dict):
        raise ConfigError(f"{where}: [computers.{name}] must be a table of fields, got "
                          f"{type(t).__name__}")
    for sub, fields in SCHEMA.items():
        tab = t.get(sub, {}) if sub else t
        at = f"[computers.{name}.{sub}]" if sub else f"[computers.{name}]"
        if not isinstance(tab, dict):
            raise ConfigError(f"{where}: {at} must be a table, got {tab!r}")
        for key, v in tab.items():
            if key.endswith("_source") or (not sub and key in SCHEMA):
                continue
            if key not in fields:
                allowed = sorted(fields) + ([k for k in SCHEMA if k] if not sub else [])
                raise ConfigError(f"{where}: {at} {key} is not a field"
                                  f"{close_matches(key, allowed)}; allowed: "
                                  f"{', '.join(allowed)} (and <field>_source)")
            kind = fields[key]
            zero = kind.endswith("0")
            ok = (isinstance(v, str) if kind == "str" else
                  isinstance(v, list) and all(isinstance(x, str) for x in v) if kind == "list"
                  else isinstance(v, (int, float)) and not isinstance(v, bool)
                  and (0 <= v if zero else 0 < v) and v < float("inf")
                  and (kind.startswith("num") or float(v).is_integer()))
            if not ok:
                what = {"str": "a string", "list": "a list of strings",
                        "int": "a whole number > 0", "num": "a number > 0",
                        "int0": "a whole number >= 0", "num0": "a number >= 0"}[kind]
                raise ConfigError(f"{where}: {at} {key} = {v!r} is not allowed; it must be "
                                  f"{what}")


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
                 if k in have and runs_on(r, k, t))
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


def runs_on(runtime: str, kind: str, t: dict) -> bool:
    """Whether ``runtime`` can use the ``kind`` unit of the computer table ``t``: the CUDA
    runtimes need an NVIDIA GPU, ``edgetpu`` an Edge TPU."""
    u = t.get(kind, {})
    if kind == "gpu" and runtime in CUDA_RUNTIMES:
        return bool(u.get("cuda_cores"))
    if kind == "npu" and runtime == "edgetpu":
        return "edge" in str(u.get("kind", "")).lower().replace(" ", "")
    return True


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
    comps = data.get("computers", {})
    for n, t in comps.items():
        check(n, t, Path(path).name)
    return {n: from_datasheet(n, t) for n, t in comps.items()}


__all__ = ["COMPUTERS", "CUDA_RUNTIMES", "SCHEMA", "TARGET_ORDER", "check", "from_datasheet",
           "load_devices", "runs_on"]
