"""The paper's ML templates (FlockAI, section 4.3, Listing 3), to subclass.

::

    class CrowdCounter(fa.ml.Counter):
        def load_model(self, path, **params):
            super().load_model(path, **params)      # an OnnxModel in self.model
            self.threshold = params.get("threshold", 0.5)
            return self

        def inference(self, data):
            density = self.model(data)
            return float(density.sum())

    counter = CrowdCounter().load_model("fixtures/models/crowd_cnn.onnx")
    task = fa.Task(counter, period_s=5.0)

An instance is a model: ``instance(frame)`` calls ``inference(frame)``; it has
``macs`` and ``params`` (copied from the loaded ONNX model, or set them
yourself for a model you load another way). Models that learn in flight
override ``update(data)``: the task runner calls it after each inference with
the frame and charges ``update_macs`` to the device.

``load_model`` keyword params that ``OnnxModel`` knows (input_size, layout,
scale, mean, std, providers, macs, threads) go to it; the rest are kept in
``self.params_``.
"""

from __future__ import annotations

import numpy as np

from ..errors import FlockAIError
from .models import Model, OnnxModel

_ONNX_KW = ("input_size", "layout", "scale", "mean", "std", "providers", "macs", "threads",
            "postprocess", "name")


class Template(Model):
    """Base of the templates (the paper's ``FlockAIMLBaseClass``)."""

    kind = "model"
    update_macs: int = 0
    model = None                 # class defaults: a subclass __init__ may skip super().__init__()
    _macs_from_model = False
    params_: dict = {}

    def __init__(self, *, macs: int | None = None, params: int = 0, name: str | None = None):
        self.model = None
        self.macs = macs
        self.params = params
        self.name = name or type(self).__name__
        self.params_: dict = {}
        self._macs_from_model = False

    # -- the paper's interface -------------------------------------------------
    def load_model(self, path, **params):
        """Load an ONNX model into ``self.model``; returns self."""
        onnx_kw = {k: params.pop(k) for k in list(params) if k in _ONNX_KW}
        self.model = OnnxModel(path, **onnx_kw)
        self.params_ = params
        self.macs = self.model.macs
        self.params = self.model.params
        self._macs_from_model = True
        return self

    def inference(self, data):
        """The prediction for ``data`` (a frame or a sensor reading): override it."""
        raise FlockAIError(f"{type(self).__name__}.inference(data) is not implemented: override it "
                           f"in your subclass (it must return the prediction)")

    def update(self, data) -> None:
        """Learn from ``data`` in flight (optional; the default learns nothing)."""

    # -- the model interface ---------------------------------------------------
    @property
    def learns_in_flight(self) -> bool:
        """Whether the subclass overrides ``update`` (it learns from each result)."""
        return type(self).update is not Template.update

    def __call__(self, frame):
        return self.inference(frame)

    def macs_for(self, frame):
        """Multiply-accumulates of one inference (the wrapped model's, or as given)."""
        if self.model is not None and self._macs_from_model:
            m = self.model.macs_for(frame)
            self.macs = self.model.macs if self.model.macs is not None else m
            return m
        return self.macs

    def _raw(self, data):
        if self.model is None:
            raise FlockAIError(f"{type(self).__name__}: no model loaded; call load_model(path) or "
                               f"override inference(data)")
        return self.model(data)


class Classifier(Template):
    """Classification: the default ``inference`` returns the arg-max class
    (its label when ``labels=[...]`` was passed to ``load_model``)."""

    kind = "classifier"

    def inference(self, data):
        out = np.asarray(self._raw(data)).reshape(-1)
        i = int(np.argmax(out))
        labels = self.params_.get("labels")
        return labels[i] if labels is not None else i


class Detector(Template):
    """Object detection: ``inference`` must return a list of detections
    (e.g. ``(x, y, w, h, score)``); the count is its length. No default."""

    kind = "detector"


class Regressor(Template):
    """Regression: the default ``inference`` returns the output as a float
    (one value) or an array."""

    kind = "regressor"

    def inference(self, data):
        out = np.asarray(self._raw(data))
        return float(out.reshape(-1)[0]) if out.size == 1 else out


class Clusterer(Template):
    """Clustering: ``inference`` returns cluster assignments; ``update`` may
    refine the clusters in flight. No default."""

    kind = "clusterer"


class Counter(Template):
    """Counting (e.g. people): the default ``inference`` returns the sum of the
    model's output, which is the count for a density-map network."""

    kind = "counter"

    def inference(self, data):
        return float(np.sum(self._raw(data)))


__all__ = ["Classifier", "Clusterer", "Counter", "Detector", "Regressor", "Template"]
