"""Moved to ``pytest_flockai.ml.task_scoring``; the old path warns once per name
(``_deprecation.py``) and will be removed."""

from .._deprecation import moved

__getattr__ = moved(__name__, {
    "ConfigError": "pytest_flockai.ml.task_scoring.ConfigError",
    "Detections": "pytest_flockai.ml.task_scoring.Detections",
    "FrameRecord": "pytest_flockai.ml.task_scoring.FrameRecord",
    "GALLERY_JPEG_QUALITY": "pytest_flockai.ml.task_scoring.GALLERY_JPEG_QUALITY",
    "Scorer": "pytest_flockai.ml.task_scoring.Scorer",
    "classification_kpis": "pytest_flockai.ml.task_scoring.classification_kpis",
    "crowd_metrics": "pytest_flockai.ml.task_scoring.crowd_metrics",
    "detection_kpis": "pytest_flockai.ml.task_scoring.detection_kpis",
    "encode_jpeg": "pytest_flockai.ml.task_scoring.encode_jpeg",
    "is_image": "pytest_flockai.ml.task_scoring.is_image",
    "parse_detections": "pytest_flockai.ml.task_scoring.parse_detections",
    "to_task_classes": "pytest_flockai.ml.task_scoring.to_task_classes",
    "truth_count": "pytest_flockai.ml.task_scoring.truth_count",
})
