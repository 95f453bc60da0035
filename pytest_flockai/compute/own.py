"""A team's own computer: a datasheet in the schema of ``compute/data/computers.toml``.

``computer(source, name=None)`` reads one and returns the ``Device`` every part of the
package takes (``predict_latency``, ``fa.drone(..., device=...)``, ``Task``,
``compare_models``, ``flockai predict-latency --computers FILE``). ``source`` is a TOML
file of ``[computers.NAME]`` tables (the layout of the package's own file, so a profile
can be copied from it and edited), or one computer's table as a dict. A table may start
from a profile of the package (``based_on = "raspberry-pi-5"``): its sub-tables are
merged field by field, so an over-clocked board or another power mode is a few lines.

It is checked where it enters, each error naming the field, the value and what is
allowed: fields the schema (``datasheets.SCHEMA``) does not know, figures that are not
positive numbers, a missing ``memory_mb``, ``memory_bandwidth_gbs`` or power figure, busy
power not above idle, an unknown runtime, a runtime none of its units can run (TensorRT
needs a ``[gpu]`` with ``cuda_cores``; ``edgetpu`` an ``[npu]`` whose ``kind`` is the Edge
TPU), a unit without a clock or peak, the name of a profile of the package.

Without a ``[mac_rule]`` (the rule for a model known only by its MAC count), it is derived
from the layer model: ResNet-18 at 224 x 224 (1.82 GMAC) on the computer's default
deployment gives ``macs_per_s`` and the deployment's per-inference overhead ``overhead_s``.

The latency of such a computer comes from its datasheet through the efficiencies fitted
on the published table, which hold nothing per computer; its ``band`` is the range of
leave-one-computer-out (``tuning.loco``): each board of the table predicted by a fit that
never saw it, as this computer is.
"""

from __future__ import annotations

import os
import tomllib
from dataclasses import replace
from pathlib import Path

from ..errors import ConfigError, close_matches
from . import runtimes as _rt
from ._device import Device
from .datasheets import COMPUTERS, TARGET_ORDER, check, from_datasheet, runs_on
from .devices import DEVICES
from .predict import efficiencies, params_for, roofline
from .published import network_cost

__all__ = ["computer", "computers"]

#: the network the MAC-count rule of a datasheet without one is derived from
RULE_NETWORK = ("resnet18", "224")


def _builtin_tables() -> dict:
    with COMPUTERS.open("rb") as fh:
        return tomllib.load(fh).get("computers", {})


def _merge(base: dict, t: dict) -> dict:
    out = {k: (dict(v) if isinstance(v, dict) else v) for k, v in base.items()}
    for k, v in t.items():
        if isinstance(v, dict) and isinstance(out.get(k), dict):
            out[k] = {**out[k], **v}
        else:
            out[k] = v
    return out


def _strict(name: str, t: dict, where: str) -> None:
    at = f"{where}: [computers.{name}]"
    if name in DEVICES:
        raise ConfigError(f"{at}: name {name!r} is a profile of the package; choose another "
                          f"name (based_on = {name!r} starts from its datasheet)")
    for sub, key in (("", "memory_mb"), ("power", "idle_w"), ("power", "busy_w")):
        if key not in (t.get(sub, {}) if sub else t):
            raise ConfigError(f"{at} {(sub + '.') if sub else ''}{key} is missing; every "
                              f"computer needs memory_mb, power.idle_w and power.busy_w")
    if t["power"]["busy_w"] <= t["power"]["idle_w"]:
        raise ConfigError(f"{at} power.busy_w = {t['power']['busy_w']!r} is not allowed; it "
                          f"must be above power.idle_w = {t['power']['idle_w']!r} (W at the "
                          f"board's input, every core busy and idle)")
    rts = t.get("runtimes")
    if not rts:
        raise ConfigError(f"{at} runtimes is missing or empty; allowed: "
                          f"{', '.join(_rt.RUNTIMES)}")
    units = [k for k in ("cpu", "gpu", "npu") if isinstance(t.get(k), dict)]
    if not units:
        raise ConfigError(f"{at} has no [cpu], [gpu] or [npu] table; a computer needs at "
                          f"least one unit")
    for k in units:
        u, unit_at = t[k], f"{where}: [computers.{name}.{k}]"
        need = (("cores", "clock_ghz", "fp32_flop_per_cycle_per_core") if k == "cpu" else
                ("clock_ghz",) if k == "gpu" else ("int8_tops",))
        for f in need:
            if f not in u:
                raise ConfigError(f"{unit_at} {f} is missing; a {k} needs {', '.join(need)}")
        if k == "gpu" and not any(u.get(f) for f in ("fp32_tflops", "fp16_tflops",
                                                     "fp16_tensor_tflops", "int8_tops")):
            raise ConfigError(f"{unit_at} has no peak; give fp32_tflops, fp16_tflops, "
                              f"fp16_tensor_tflops or int8_tops (dense, not sparse)")
    if ("cpu" in units or "gpu" in units) and "memory_bandwidth_gbs" not in t:
        raise ConfigError(f"{at} memory_bandwidth_gbs is missing; the datasheet's memory "
                          f"bandwidth (GB/s) sets how fast layers that move data run")
    for r in rts:
        if r not in _rt.RUNTIMES:
            raise ConfigError(f"{at} runtimes: {r!r} is not a runtime"
                              f"{close_matches(r, _rt.RUNTIMES)}; allowed: "
                              f"{', '.join(_rt.RUNTIMES)}")
        if not any(k in units and runs_on(r, k, t) for k in TARGET_ORDER[r]):
            why = {"tensorrt": "a [gpu] with cuda_cores (an NVIDIA GPU)",
                   "edgetpu": "an [npu] whose kind is \"Edge TPU\""}.get(
                r, f"one of: {', '.join(f'[{k}]' for k in TARGET_ORDER[r])}")
            raise ConfigError(f"{at} runtimes: {r!r} cannot run on this computer; it needs "
                              f"{why}")


def _mac_rule(dev: Device) -> Device:
    """``dev`` with the MAC-count rule derived from the layer model (module docstring)."""
    cost = network_cost(*RULE_NETWORK)
    dep = _rt.resolve(dev, where=f"computer {dev.name!r}")
    prm = params_for(efficiencies(), dep)
    secs = roofline(cost, dev, dep, prm)[0]
    unit = dev.unit(dep.target)
    over = prm["overhead_s"] / (unit.clock_ghz if unit.clock_ghz > 0 else 1.0)
    macs = float(sum(n.macs for n in cost.nodes))
    src = (f"derived: the layer model on {RULE_NETWORK[0]}-{RULE_NETWORK[1]} "
           f"({macs / 1e9:.2f} GMAC) on {dep.key}: {secs * 1e3:.2f} ms")
    return replace(dev, macs_per_s=macs / max(secs - over, 1e-9), overhead_s=over,
                   sources=dev.sources + (("mac_rule.macs_per_s_source", src),
                                          ("mac_rule.overhead_s_source", src)))


def _tables(source) -> tuple[dict, str]:
    if isinstance(source, dict):
        return source, "computer"
    if not isinstance(source, (str, os.PathLike)):
        raise ConfigError(f"source = {source!r} is not a datasheet; expected a TOML file's "
                          f"path or a dict of one computer's fields")
    path = Path(source)
    if not path.is_file():
        raise ConfigError(f"source = {str(path)!r}: no such file (a TOML file of "
                          f"[computers.NAME] tables)")
    try:
        with path.open("rb") as fh:
            data = tomllib.load(fh)
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        raise ConfigError(f"source = {str(path)!r} is not TOML: {e}") from None
    comps = data.get("computers")
    if not isinstance(comps, dict) or not comps:
        raise ConfigError(f"{path.name}: no [computers.NAME] table; a datasheet file holds "
                          f"one per computer, in the layout of the package's computers.toml")
    return comps, path.name


def computers(source) -> dict[str, Device]:
    """Every computer of the datasheet file ``source``, by name (``computer`` checks each)."""
    if isinstance(source, dict):
        raise ConfigError("source: computers() reads a file; for one table use "
                          "computer(table, name=...)")
    comps, where = _tables(source)
    return {n: _one(n, t, where) for n, t in comps.items()}


def computer(source, name: str | None = None) -> Device:
    """One computer from a datasheet (module docstring): ``source`` a TOML file (``name``:
    which of its computers; may be left out when it holds one) or a dict of one computer's
    fields (``name`` required)."""
    comps, where = _tables(source)
    if isinstance(source, dict):
        if not name:
            raise ConfigError("name is missing: a computer given as a dict needs name=...")
        return _one(str(name), source, where)
    if name is None:
        if len(comps) > 1:
            raise ConfigError(f"{where} holds {len(comps)} computers ({', '.join(comps)}); "
                              f"name one: computer(path, name=...)")
        name = next(iter(comps))
    if name not in comps:
        raise ConfigError(f"name = {name!r} is not a computer of {where}"
                          f"{close_matches(name, comps)}; allowed: {', '.join(comps)}")
    return _one(name, comps[name], where)


def _one(name: str, t, where: str) -> Device:
    if not isinstance(t, dict):
        raise ConfigError(f"{where}: [computers.{name}] must be a table of fields, got "
                          f"{type(t).__name__}")
    t = dict(t)
    base = t.pop("based_on", None)
    if base is not None:
        tables = _builtin_tables()
        if base not in tables:
            raise ConfigError(f"{where}: [computers.{name}] based_on = {base!r} is not a "
                              f"profile{close_matches(str(base), tables)}; allowed: "
                              f"{', '.join(sorted(tables))}")
        # its MAC-count rule is an estimate for its own clock: derived anew unless given
        t = _merge({k: v for k, v in tables[base].items() if k != "mac_rule"}, t)
    check(name, t, where)
    _strict(name, t, where)
    rule = isinstance(t.get("mac_rule"), dict) and {"macs_per_s", "overhead_s"} <= set(t["mac_rule"])
    full = t if rule else {**t, "mac_rule": {"macs_per_s": 1.0, "overhead_s": 0.0}}
    dev = from_datasheet(name, full)
    what = f"based on {base}, " if base else ""
    dev = replace(dev, source=f"{name}: {where} (a team's own datasheet, {what}never tuned: "
                              f"its band is the leave-one-computer-out range)")
    return dev if rule else _mac_rule(dev)

