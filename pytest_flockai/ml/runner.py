"""Moved to ``pytest_flockai.ml.task_runner``; the old path warns once per name
(``_deprecation.py``) and will be removed."""

from .._deprecation import moved

__getattr__ = moved(__name__, {
    "ConfigError": "pytest_flockai.ml.task_runner.ConfigError",
    "DeviceClock": "pytest_flockai.ml.task_runner.DeviceClock",
    "InferenceEvent": "pytest_flockai.ml.task_runner.InferenceEvent",
    "InferenceTimer": "pytest_flockai.ml.task_runner.InferenceTimer",
    "JPEG_MACS_PER_PIXEL": "pytest_flockai.ml.task_runner.JPEG_MACS_PER_PIXEL",
    "STANDALONE_DEVICE": "pytest_flockai.ml.task_runner.STANDALONE_DEVICE",
    "Scorer": "pytest_flockai.ml.task_runner.Scorer",
    "SortedValues": "pytest_flockai.ml.task_runner.SortedValues",
    "Task": "pytest_flockai.ml.task_runner.Task",
    "TaskRunner": "pytest_flockai.ml.task_runner.TaskRunner",
    "Template": "pytest_flockai.ml.task_runner.Template",
    "annotate": "pytest_flockai.ml.task_runner.annotate",
    "calibrate": "pytest_flockai.ml.task_runner.calibrate",
    "compute_seconds": "pytest_flockai.ml.task_runner.compute_seconds",
    "decode_jpeg": "pytest_flockai.ml.task_runner.decode_jpeg",
    "encode_jpeg": "pytest_flockai.ml.task_runner.encode_jpeg",
    "invalid_prediction": "pytest_flockai.ml.task_runner.invalid_prediction",
    "is_image": "pytest_flockai.ml.task_runner.is_image",
    "is_measured": "pytest_flockai.ml.task_runner.is_measured",
    "memo": "pytest_flockai.ml.task_runner.memo",
    "resolve_device": "pytest_flockai.ml.task_runner.resolve_device",
    "scale_to_device": "pytest_flockai.compute.latency.scale_to_device",
})
