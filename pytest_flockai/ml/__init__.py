"""ML deployment: models, the paper's templates, tasks and their metrics.

- ``OnnxModel``, ``OpenCVModel``, ``PythonModel``: ``model(frame) -> prediction``
  with ``macs`` and ``params``;
- ``Classifier``, ``Detector``, ``Regressor``, ``Clusterer``, ``Counter``:
  templates to subclass (the paper's Listing 3);
- ``Task`` and ``TaskRunner``: what runs where, executed on the simulated clock;
- ``count_macs``: MACs and parameters of an ONNX graph.
"""

from .macs import MacReport, count_macs
from .metrics import count_of, crowd_metrics
from .models import Model, OnnxModel, OpenCVModel, PythonModel
from .task import InferenceEvent, Task, TaskRunner
from .templates import Classifier, Clusterer, Counter, Detector, Regressor, Template

__all__ = ["Classifier", "Clusterer", "Counter", "Detector", "InferenceEvent", "MacReport", "Model",
           "OnnxModel", "OpenCVModel", "PythonModel", "Regressor", "Task", "TaskRunner", "Template",
           "count_macs", "count_of", "crowd_metrics"]
