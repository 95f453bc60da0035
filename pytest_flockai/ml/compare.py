"""Moved to ``pytest_flockai.ml.model_choice``; the old path warns once per name
(``_deprecation.py``) and will be removed."""

from .._deprecation import moved

__getattr__ = moved(__name__, {
    "ACCURACY": "pytest_flockai.ml.model_choice.ACCURACY",
    "ConfigError": "pytest_flockai.ml.model_choice.ConfigError",
    "InferenceTimer": "pytest_flockai.ml.model_choice.InferenceTimer",
    "LatencyFallbackWarning": "pytest_flockai.ml.model_choice.LatencyFallbackWarning",
    "Task": "pytest_flockai.ml.model_choice.Task",
    "as_model": "pytest_flockai.ml.model_choice.as_model",
    "compare_models": "pytest_flockai.ml.model_choice.compare_models",
    "evaluate_dataset": "pytest_flockai.ml.model_choice.evaluate_dataset",
    "resolve_device": "pytest_flockai.ml.model_choice.resolve_device",
})
