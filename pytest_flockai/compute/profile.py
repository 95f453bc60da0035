"""Measured device profiles: what ``flockai profile-device`` wrote, loaded and checked.

``profile("profile.json") -> MeasuredDevice``: the computer the profile was measured
on (host facts, runtime and its version, threads), per model the measured latency
samples (seconds, one per timed run after warm-up), and the busy / idle power when a
watt meter or the Jetson's rails gave them. A model is identified by the SHA-256 of
its ONNX file (and of its external data files, ``model_sha256``), so a renamed copy
still matches and an edited one does not. ``sample_latency(model, rng)`` draws one
inference's latency from the measured samples with the caller's seeded generator:
the same seed gives the same draws, and p95 differs from p50 as it did on the
computer. A file that is not such a profile is a ``ConfigError`` naming the field.
"""

from __future__ import annotations

import functools
import hashlib
import json
import math
import os
from dataclasses import dataclass, field

import numpy as np
import onnx

from ..errors import ConfigError

SCHEMA = "flockai-device-profile/1"
RUNTIMES = ("onnxruntime", "tflite", "ncnn", "openvino", "opencv-dnn", "pytorch", "tensorrt",
            "edgetpu")
TARGETS = ("cpu", "gpu", "npu")
PRECISIONS = ("fp32", "fp16", "int8")


def model_format(path) -> str:
    """``tflite`` for a ``.tflite`` file (by name, then by its FlatBuffer identifier
    ``TFL3``), ``ncnn`` for an ncnn ``.param`` file, else ``onnx``."""
    p = os.fspath(path)
    if p.lower().endswith(".tflite"):
        return "tflite"
    if p.lower().endswith(".param"):
        return "ncnn"
    try:
        with open(p, "rb") as fh:
            head = fh.read(8)
    except OSError:
        return "onnx"
    return "tflite" if head[4:8] == b"TFL3" else "onnx"


def model_sha256(path) -> str:
    """SHA-256 of an ONNX file's bytes, then (when it has any) of each external data file
    it names, in sorted order; the plain ``sha256sum`` of a self-contained file (and of a
    ``.tflite`` file; of an ncnn ``.param`` file followed by its ``.bin``). Memoised on the path, size and modification time."""
    p = os.fspath(path)
    if not os.path.isfile(p):
        raise ConfigError(f"model path = {p!r} does not exist or is not a file; expected an "
                          f".onnx (or .tflite, ncnn .param) file")
    st = os.stat(p)
    return _sha256(os.path.abspath(p), st.st_size, st.st_mtime_ns, model_format(p))


@functools.lru_cache(maxsize=256)
def _sha256(p: str, size: int, mtime_ns: int, fmt: str = "onnx") -> str:
    h = hashlib.sha256()
    with open(p, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    if fmt == "ncnn":                   # the .param, then its .bin
        weights = p[:-len(".param")] + ".bin"
        if os.path.isfile(weights):
            with open(weights, "rb") as fh:
                for block in iter(lambda: fh.read(1 << 20), b""):
                    h.update(block)
        return h.hexdigest()
    if fmt == "tflite":
        return h.hexdigest()
    try:
        proto = onnx.load(p, load_external_data=False)
    except Exception as e:
        raise ConfigError(f"model path = {p!r} is not a valid ONNX model: {e}") from None
    locations = sorted({e.value for t in onnx.external_data_helper._get_all_tensors(proto)
                        for e in t.external_data if e.key == "location"})
    if not locations:
        return h.hexdigest()
    for loc in locations:
        with open(os.path.join(os.path.dirname(p) or ".", loc), "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                h.update(block)
    return h.hexdigest()


@dataclass(frozen=True)
class MeasuredModel:
    """One profiled model: its identity and the latency of each timed run (s)."""

    name: str
    sha256: str
    latency_s: tuple[float, ...]
    input_shape: tuple[int, ...] | None = None
    warmup: int = 0
    macs: int | None = None

    def percentile(self, q: float) -> float:
        return float(np.percentile(np.asarray(self.latency_s), q))

    def draw(self, rng: np.random.Generator, size=None):
        """Measured latencies drawn uniformly with ``rng`` (each one of the samples)."""
        idx = rng.integers(len(self.latency_s), size=size)
        return float(self.latency_s[int(idx)]) if size is None else \
            np.asarray(self.latency_s, dtype=float)[idx]


@dataclass(frozen=True)
class MeasuredDevice:
    """A computer as measured by ``flockai profile-device``."""

    name: str
    runtime: str
    runtime_version: str
    target: str
    precision: str
    threads: int | None
    models: dict[str, MeasuredModel]               # sha256 -> model
    host: dict = field(default_factory=dict)
    busy_w: float | None = None
    idle_w: float | None = None
    power_source: str | None = None
    path: str = ""

    def model(self, model) -> MeasuredModel:
        """The profiled model matching ``model``: an ONNX path, an OnnxModel (its
        file), a SHA-256, or a profiled model's name; ConfigError naming it otherwise."""
        if isinstance(model, MeasuredModel):
            return model
        key = model
        if isinstance(model, (bytes, bytearray)):      # a self-contained file's bytes
            key = hashlib.sha256(model).hexdigest()
        elif not isinstance(model, str) or not (len(model) == 64 and model in self.models):
            path = getattr(model, "path", model)
            if isinstance(path, (str, os.PathLike)) and os.path.isfile(path):
                key = model_sha256(path)
        if isinstance(key, str):
            if key in self.models:
                return self.models[key]
            named = [m for m in self.models.values() if m.name == key]
            if len(named) == 1:
                return named[0]
        have = ", ".join(f"{m.name} ({m.sha256[:12]})" for m in self.models.values())
        what = (f"<{len(model)} bytes of ONNX, SHA-256 {key[:12]}>"
                if isinstance(model, (bytes, bytearray)) else
                repr(getattr(model, "name", None) or getattr(getattr(model, "graph", None), "name",
                                                              None) or model))
        raise ConfigError(f"model = {what} was not profiled on "
                          f"{self.name!r} (profile {self.path!r}; SHA-256 of the ONNX file "
                          f"compared); profiled: {have}")

    def latency_samples(self, model) -> np.ndarray:
        """The measured latencies of ``model`` in seconds, in measurement order."""
        return np.asarray(self.model(model).latency_s, dtype=float)

    def sample_latency(self, model, rng, size=None):
        """One inference's latency (s): one of the measured samples, drawn uniformly with
        ``rng`` (a ``numpy.random.Generator``, or an int seed); ``size``: an array of
        that many draws instead of one float."""
        g = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
        return self.model(model).draw(g, size)

    def energy_j(self, model) -> float | None:
        """Energy per inference above idle (J): median latency x (busy - idle power);
        None unless the profile has both powers."""
        if self.busy_w is None or self.idle_w is None:
            return None
        return self.model(model).percentile(50) * max(0.0, self.busy_w - self.idle_w)


_CHECKS = {
    "str": lambda v: isinstance(v, str) and v != "",
    "dict": lambda v: isinstance(v, dict),
    "list": lambda v: isinstance(v, list),
    "int": lambda v: isinstance(v, int) and not isinstance(v, bool) and v >= 0,
    "number": lambda v: (isinstance(v, (int, float)) and not isinstance(v, bool)
                         and math.isfinite(v) and v >= 0),
}


def _field(doc, key, where, kind, *, allowed=None, optional=False):
    """``doc[key]`` checked: ``kind`` starts with str, dict, list, int or number."""
    if key not in doc or doc[key] is None:
        if optional:
            return None
        raise ConfigError(f"{where}: field {key!r} is missing; expected {kind}")
    v = doc[key]
    if not _CHECKS[kind.split()[0]](v) or (allowed is not None and v not in allowed):
        what = f"one of {list(allowed)}" if allowed is not None else kind
        raise ConfigError(f"{where}: field {key!r} = {v!r:.80} is not allowed; expected {what}")
    return v


def from_dict(doc, where: str = "profile") -> MeasuredDevice:
    """A MeasuredDevice from a profile's parsed JSON; ConfigError naming the bad field."""
    if not isinstance(doc, dict):
        raise ConfigError(f"{where}: expected a JSON object with schema {SCHEMA!r}, got "
                          f"{type(doc).__name__}")
    _field(doc, "schema", where, "str", allowed=(SCHEMA,))
    rt = _field(doc, "runtime", where, "dict")
    rw = f"{where}: runtime"
    runtime = _field(rt, "name", rw, "str", allowed=RUNTIMES)
    threads = _field(rt, "threads", rw, "int >= 0", optional=True)
    power = _field(doc, "power", where, "dict", optional=True) or {}
    models: dict[str, MeasuredModel] = {}
    items = _field(doc, "models", where, "list of profiled models")
    if not items:
        raise ConfigError(f"{where}: field 'models' = [] is not allowed; expected at least "
                          f"one profiled model")
    for i, m in enumerate(items):
        mw = f"{where}: models[{i}]"
        if not isinstance(m, dict):
            raise ConfigError(f"{mw} = {m!r} is not allowed; expected an object")
        sha = _field(m, "sha256", mw, "str")
        if len(sha) != 64 or any(c not in "0123456789abcdef" for c in sha):
            raise ConfigError(f"{mw}: field 'sha256' = {sha!r} is not allowed; expected 64 "
                              f"lower-case hex digits")
        lat = _field(m, "latency_s", mw, "list of latencies (s)")
        if not lat or not all(isinstance(x, (int, float)) and not isinstance(x, bool)
                              and math.isfinite(x) and x > 0 for x in lat):
            raise ConfigError(f"{mw}: field 'latency_s' = {lat!r:.80} is not allowed; expected "
                              f"a non-empty list of latencies > 0 (s)")
        shape = _field(m, "input_shape", mw, "list of dims", optional=True)
        if shape is not None and not all(isinstance(d, int) and d > 0 for d in shape):
            raise ConfigError(f"{mw}: field 'input_shape' = {shape!r} is not allowed; "
                              f"expected whole numbers > 0")
        models[sha] = MeasuredModel(_field(m, "name", mw, "str"), sha,
                                    tuple(float(x) for x in lat),
                                    tuple(shape) if shape is not None else None,
                                    _field(m, "warmup", mw, "int >= 0", optional=True) or 0,
                                    _field(m, "macs", mw, "int >= 0", optional=True))
    return MeasuredDevice(
        name=_field(doc, "name", where, "str"), runtime=runtime,
        runtime_version=_field(rt, "version", rw, "str"),
        target=_field(rt, "target", rw, "str", allowed=TARGETS),
        precision=_field(rt, "precision", rw, "str", allowed=PRECISIONS),
        threads=threads, models=models,
        host=_field(doc, "host", where, "dict", optional=True) or {},
        busy_w=_field(power, "busy_w", f"{where}: power", "number >= 0 (W)", optional=True),
        idle_w=_field(power, "idle_w", f"{where}: power", "number >= 0 (W)", optional=True),
        power_source=_field(power, "source", f"{where}: power", "str", optional=True),
        path=where)


def profile(path) -> MeasuredDevice:
    """Load and check a profile written by ``flockai profile-device``."""
    p = os.fspath(path)
    where = f"profile {p!r}"
    try:
        with open(p, encoding="utf-8") as fh:
            doc = json.load(fh)
    except FileNotFoundError:
        raise ConfigError(f"profile path = {p!r} does not exist; expected a JSON file written "
                          f"by flockai profile-device") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise ConfigError(f"{where} is not a profile (not readable JSON: {e}); expected a "
                          f"file written by flockai profile-device") from None
    dev = from_dict(doc, where)
    return MeasuredDevice(**{**dev.__dict__, "path": p})


__all__ = ["MeasuredDevice", "MeasuredModel", "from_dict", "model_format", "model_sha256",
           "profile"]
