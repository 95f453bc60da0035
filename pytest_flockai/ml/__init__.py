"""ML deployment: models, the paper's templates, tasks and their metrics.

- ``OnnxModel``, ``OpenCVModel``, ``PythonModel``: ``model(frame) -> prediction``
  with ``macs`` and ``params``;
- ``Classifier``, ``Detector``, ``Regressor``, ``Clusterer``, ``Counter``:
  templates to subclass (the paper's Listing 3);
- ``Task`` and ``TaskRunner``: what runs where, executed on the simulated clock;
- ``Detections``, ``parse_detections``: detector outputs (boxes, YOLO heads) read
  into one shape; ``detection_kpis``: COCO detection metrics of ``FrameRecord`` s;
- ``detection_envelope``: a KPI over altitude x speed, ``altitude_band`` where it holds;
- ``count_macs``: MACs and parameters of an ONNX graph;
- ``Oracle``: the frame's truth boxes as detections (optionally degraded), no pixels;
  ``MarkerDetector``: ArUco markers through OpenCV;
- ``evaluate_dataset``: a task's model over a labelled folder, each image once,
  offline; ``analyse``: PR curves, per-class AP, confusion matrix, F1-best
  threshold from COCOeval's arrays;
- ``shipped("detector")``: the models shipped in the package; ``compare_models``:
  several models on the same frames, accuracy next to latency, energy, endurance.
"""

from .analysis import analyse, write_coco_pair
from .dataset_eval import DatasetEvaluation, evaluate_dataset
from .detections import Detections, parse_detections
from .envelope import altitude_band
from .envelope import envelope as detection_envelope
from .evaluation import FrameRecord, detection_kpis
from .fiducial import MarkerDetector
from .jpeg import decode_jpeg, encode_jpeg
from .macs import MacReport, count_macs
from .metrics import count_of, crowd_metrics
from .model_choice import compare_models
from .models import Model, OnnxModel, OpenCVModel, PythonModel
from .oracle import Oracle, OracleFrame
from .shipped import SHIPPED, shipped, shipped_path
from .task import Task
from .task_runner import DeviceClock, InferenceEvent, TaskRunner
from .templates import Classifier, Clusterer, Counter, Detector, Regressor, Template

__all__ = ["Classifier", "Clusterer", "Counter", "DatasetEvaluation", "Detections", "Detector",
           "DeviceClock", "SHIPPED", "analyse", "compare_models", "evaluate_dataset", "shipped", "shipped_path",
           "write_coco_pair",
           "FrameRecord", "InferenceEvent", "MacReport", "MarkerDetector", "Model", "OnnxModel",
           "OpenCVModel", "Oracle", "OracleFrame",
           "PythonModel", "Regressor", "Task", "TaskRunner", "Template", "count_macs", "count_of",
           "crowd_metrics", "decode_jpeg", "encode_jpeg", "parse_detections",
           "altitude_band", "detection_envelope", "detection_kpis"]
