"""``flockai predict-latency MODEL.onnx``: a network's predicted inference latency on the
computer profiles, from the shell (``predict.predict_latency`` for each computer and each
runtime it lists, or for the ones asked for).

    flockai predict-latency yolov8n.onnx --input-shape 1x3x640x640
    flockai predict-latency model.onnx --computer raspberry-pi-5 --runtime ncnn --precision int8
    flockai predict-latency model.onnx --computers my_boards.toml --computer rock-5b

One row per (computer, runtime): the deployment (runtime/target/precision and threads), the
predicted milliseconds, the held-out range around it (``LatencyPrediction.band``) and the
energy above idle; a quantized (int8) model on a deployment that cannot run int8 is marked
``*`` (its default precision is shown). A deployment a computer cannot run is left out when the computers or the
runtime were not both named, and listed under the table; when both were named it is the usage
error it is for ``predict_latency``. ``--json`` also writes the rows (atomically).
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

from .._io import atomic_write
from ..errors import ConfigError
from . import own as _own
from . import runtimes as _rt
from .devices import device, devices
from .graph import DynamicInputError, NetworkCost, analyze
from .predict import predict_latency
from .profiler import _parse_shape

__all__ = ["add_parser", "rows", "run_cli"]


def add_parser(sub) -> None:
    p = sub.add_parser("predict-latency", help="predict an ONNX model's inference latency on "
                                               "the computer profiles",
                       description="Predict one inference of MODEL.onnx on each computer "
                                   "profile and runtime (or the ones named), from its layers, "
                                   "with the range the held-out published measurements give.",
                       epilog="examples: flockai predict-latency yolov8n.onnx --input-shape "
                              "1x3x640x640;  flockai predict-latency model.onnx --computer "
                              "raspberry-pi-5 --runtime ncnn --precision int8")
    p.add_argument("model", type=Path, metavar="MODEL.onnx")
    p.add_argument("--computer", action="append", default=None, metavar="NAME",
                   help="a computer profile (repeat for several; default: every profile with "
                        "a datasheet)")
    p.add_argument("--computers", type=Path, default=None, metavar="FILE.toml",
                   help="your own computers' datasheets ([computers.NAME] tables, the layout "
                        "of the package's computers.toml): added to the profiles, or, with "
                        "--computer, nameable")
    p.add_argument("--runtime", default=None, help="one runtime (default: each the computer "
                                                   "lists)")
    p.add_argument("--precision", default=None, help="fp32, fp16 or int8 (default: the "
                                                     "runtime's; int8 for a quantized graph)")
    p.add_argument("--target", default=None, help="cpu, gpu or npu")
    p.add_argument("--threads", type=int, default=None, help="CPU threads (default: the "
                                                             "runtime's)")
    p.add_argument("--input-shape", default=None, help="the input's shape, e.g. 1x3x640x640, "
                                                       "where it is dynamic")
    p.add_argument("--json", type=Path, default=None, help="also write the rows to this JSON "
                                                           "file")


def rows(model, computers=None, *, runtime=None, precision=None, target=None, threads=None,
         input_shape=None, own=None) -> tuple[NetworkCost, list[dict], list[str]]:
    """(the model's ``NetworkCost``, one dict per predicted deployment, why each left-out
    deployment was left out); ``model`` an ONNX path; ``own``: a datasheet file of the
    team's own computers (``own.computers``), added after the profiles. The names and the
    datasheets are checked before the graph is read."""
    _rt.check_names(runtime, precision, target, threads)
    mine = _own.computers(own) if own is not None else {}
    for name in computers or ():
        if name not in mine:
            try:
                device(name)
            except ConfigError as e:
                raise ConfigError(f"--computer = {name!r}: {e}"
                                  + (f"; or one of {own}: {', '.join(mine)}" if mine else "")
                                  ) from None
    try:
        cost = analyze(model, input_shape)
    except DynamicInputError as e:      # in the shell's terms: --input-shape, not input_shape=
        given = "x".join(map(str, input_shape)) if input_shape else None
        raise ConfigError(f"--input-shape = {given!r}: input {e.input_name!r} of "
                          f"{Path(model).stem!r} has dims {e.dims}; give its full shape, e.g. "
                          f"--input-shape 1x3x480x640") from None
    names = list(computers) if computers else devices() + list(mine)
    strict = bool(computers) and runtime is not None
    out, left = [], []
    for name in names:
        dev = mine[name] if name in mine else device(name)
        if not dev.deployments:
            left.append(f"{name}: no datasheet")
            continue
        for rt in [runtime] if runtime is not None else list(dev.runtimes):
            try:
                with warnings.catch_warnings(record=True) as said:
                    warnings.simplefilter("always", _rt.ModelPrecisionWarning)
                    p = predict_latency(cost, dev, runtime=rt, precision=precision,
                                        target=target, threads=threads)
            except ConfigError as e:            # what this computer cannot run
                if strict:
                    raise
                left.append(f"{name}/{rt}: {e}")
                continue
            notes = [str(w.message) for w in said
                     if issubclass(w.category, _rt.ModelPrecisionWarning)]
            out.append({"computer": name, **p.to_dict(), "milliseconds": p.milliseconds,
                        "int8_fallback": any(issubclass(w.category, _rt.QuantizedModelWarning)
                                             for w in said),
                        "fp16_fallback": any(issubclass(w.category, _rt.HalfModelWarning)
                                             for w in said),
                        "precision_warning": notes[0] if notes else None})
    return cost, out, left


def run_cli(a) -> int:
    cost, found, left = rows(a.model, a.computer, runtime=a.runtime, precision=a.precision,
                             target=a.target, threads=a.threads,
                             input_shape=_parse_shape(a.input_shape), own=a.computers)
    layers = sum(n.macs for n in cost.nodes if n.kind in ("conv", "dwconv", "matmul"))
    print(f"flockai predict-latency: {cost.name}: {cost.macs / 1e9:.3g} GMAC "
          f"({layers / 1e9:.3g} in convolutions and matrix products, as MACs are published), "
          f"{len(cost.run_nodes)} kernels, input {'x'.join(map(str, cost.input_shape or ()))}"
          + (f", quantized ({cost.meta['int8']})" if cost.meta.get("int8") else ""))
    print(f"{'computer':24s} {'runtime/target/precision':26s} {'threads':>7s} {'ms':>10s} "
          f"{'held-out range (ms)':>21s} {'mJ above idle':>13s}")
    for r in found:
        dep = f"{r['runtime']}/{r['target']}/{r['precision']}" + (
            "*" if r["precision_warning"] else "") + ("~" if r["tuned"] is False else "")
        lo, hi = (1e3 * b for b in r["band"])
        thr = "-" if r["target"] != "cpu" else r["threads"] or "all"
        print(f"{r['computer']:24s} {dep:26s} {thr:>7} "
              f"{r['milliseconds']:10.2f} {f'{lo:.2f}-{hi:.2f}':>21s} "
              f"{1e3 * r['energy_j']:13.2f}")
    if any(r["int8_fallback"] for r in found):
        print("  * the model is quantized (int8) and this deployment cannot run int8: its "
              "default precision is shown")
    if any(r["fp16_fallback"] for r in found):
        print("  * the model's weights are fp16 and this deployment cannot run fp16: its "
              "default precision is shown")
    other = [r["precision_warning"] for r in found if r["precision_warning"]
             and not r["int8_fallback"] and not r["fp16_fallback"]]
    if other:                                   # the Edge TPU and a float graph
        print("  * " + other[0].split(": ", 1)[-1])
    if any(r["tuned"] is False for r in found):
        print("  ~ no published measurement of this runtime and precision was fitted: its "
              "efficiency is borrowed from the runtime's other precisions or the unit's other "
              "runtimes (docs: explanation/latency)")
    for why in left:
        print(f"  left out: {why}")
    if a.json is not None:
        doc = {"model": str(a.model), "macs": cost.macs, "layer_macs": layers, "rows": found,
               "left_out": left}
        atomic_write(a.json, lambda fh: fh.write(json.dumps(doc, indent=1) + "\n"))
    return 0
