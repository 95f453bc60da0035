"""Sweeps: fly one mission over many scenario variants, one DataFrame row each.

``fa.sweep(base_mission, payload_kg=[0, 0.2], wind_mps=[0, 6], budgets=...)``
(see ``runner.sweep``; the axes in ``axes.py``, the sampling methods in
``design.py``, the envelope picture and CSV in ``envelope.py``). The core
needs no pytest; ``@pytest.mark.flockai_sweep`` (``harness/sweeps.py``) flies a
sweep inside a test.
"""

from .axes import MISSION_AXES
from .design import METHODS
from .runner import BACKENDS, choose_backend, default_workers, sweep

__all__ = ["BACKENDS", "METHODS", "MISSION_AXES", "choose_backend", "default_workers", "sweep"]
