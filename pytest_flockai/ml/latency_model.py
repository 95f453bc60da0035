"""Device seconds of one inference of a task's model on one computer (the runner's clock).

Which rule applies (``InferenceTimer.method``):

- ``"measured"``: the computer is a measured profile (``compute.profile``, written by
  ``flockai profile-device``): each inference's latency is a seeded draw from the measured
  samples of that model, so p95 differs from p50 as it does on the drone;
- ``"roofline"``: an ``OnnxModel`` whose graph is known (no ``macs=`` given), on a computer
  with a datasheet: ``compute.predict_latency`` at the frame's input shape, for the task's
  runtime, target, precision and threads (deterministic; memoised per input shape); a
  quantized (int8) graph runs at int8 unless the task or the drone states a precision;
- ``"macs"``: any other model (a MAC count stated by the user: ``PythonModel``,
  ``OpenCVModel``, templates): the computer's MAC-count rule ``overhead_s + macs /
  macs_per_s``.
"""

from __future__ import annotations

import warnings

import numpy as np

from ..compute import runtimes as _rt
from ..compute.graph import half_weights, quantization
from ..compute.predict import mac_rule_seconds, predict_latency
from .models import OnnxModel


def graph_model(model):
    """The ``OnnxModel`` whose layers give the latency (a template's inner one), or None
    when the model is known only by a stated MAC count."""
    inner = getattr(model, "model", None) if not isinstance(model, OnnxModel) else model
    if isinstance(inner, OnnxModel) and inner._macs_given is None and inner._proto is not None:
        return inner
    return None


def is_measured(dev) -> bool:
    """A computer whose latencies come from a measured profile (``compute.profile``)."""
    return getattr(dev, "measured", None) is not None


def input_shape(model: OnnxModel, frame) -> tuple[int, ...]:
    h, w = model._target_hw(frame)
    c = model.channels
    return (1, c, h, w) if model.layout == "NCHW" else (1, h, w, c)


class InferenceTimer:
    """Seconds of one inference of ``task``'s model on ``device`` (see the module docstring).

    ``rng``: the generator measured profiles draw from (spawned by the runner)."""

    def __init__(self, task, device, rng=None):
        self.task, self.device = task, device
        self.rng = rng if rng is not None else np.random.default_rng(0)
        self.deployment = None
        self._cache: dict = {}
        gm = graph_model(task.model)
        if is_measured(device):
            self.method = "measured"
        elif gm is not None and device.deployments:
            self.method = "roofline"
        else:
            self.method = "macs"
        if device.deployments and not is_measured(device):
            quant = quantization(gm._proto.graph) if gm is not None else None
            half = not quant and gm is not None and half_weights(gm._proto.graph)
            self.deployment = _rt.resolve(device, task.runtime, task.precision, task.target,
                                          task.threads, where=f"task {task.name!r} on "
                                                              f"{device.name!r}",
                                          quantized=quant, half=half)
        dep = self.deployment
        if task.latency == "measured" and gm is not None and dep is not None \
                and dep.target != "cpu":
            warnings.warn(f"task {task.name!r}: latency='measured' times the model on this "
                          f"host's CPU and scales the time to one core of {device.name!r}'s "
                          f"CPU, but the task runs with {dep.runtime} on its {dep.target}: "
                          f"for that time use latency='modeled' (the layer model) or a "
                          f"measured profile (flockai profile-device)", UserWarning,
                          stacklevel=2)
        #: the share of the computer's busy power above idle an inference draws (on a CPU,
        #: the deployment's threads over its cores: ``compute.runtimes.power_share``); 1 for
        #: a measured profile (its busy power was measured at its own threads)
        self.power_share = (1.0 if self.deployment is None else
                            _rt.power_share(self.deployment,
                                            device.unit(self.deployment.target)))

    def seconds(self, model, frame, macs) -> float:
        """Device seconds of one inference on ``frame`` (``macs``: its MAC count)."""
        if self.method == "measured":
            return float(self.device.measured.sample_latency(model, self.rng))
        if self.method == "roofline":
            gm = graph_model(model)
            if gm is not None:
                shape = input_shape(gm, frame)
                key = (id(gm), shape)
                hit = self._cache.get(key)
                if hit is None:
                    d = self.deployment
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")       # shared-fallback warnings
                        hit = predict_latency(gm, self.device, runtime=d.runtime,
                                              precision=d.precision, target=d.target,
                                              threads=d.threads, input_shape=shape).seconds
                    self._cache[key] = hit
                return hit
        return mac_rule_seconds(float(macs or 0.0), self.device)

    def describe(self) -> dict:
        d = self.deployment.to_dict() if self.deployment is not None else {}
        return {"device": getattr(self.device, "name", None), "latency_model": self.method, **d}


__all__ = ["InferenceTimer", "graph_model", "input_shape", "is_measured"]
