"""Monitoring probes: the paper's Table 1 metrics, custom probes, live subscriptions."""

from .base import FunctionProbe, Metric, Probe
from .builtin import (
    CommProbe,
    ComputeProbe,
    EnergyProbe,
    FlightProbe,
    MLProbe,
    TaskProbe,
    default_probes,
)
from .hub import ProbeHub, RunView, resolve_probes

__all__ = ["CommProbe", "ComputeProbe", "EnergyProbe", "FlightProbe", "FunctionProbe", "MLProbe", "Metric", "TaskProbe",
           "Probe", "ProbeHub", "RunView", "default_probes", "resolve_probes"]
