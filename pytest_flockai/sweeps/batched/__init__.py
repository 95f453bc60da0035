"""The batched sweep backend (``fa.sweep(..., backend="mjx")``): every variant of
a sweep in one batch, MuJoCo's physics in MJX (``jax.vmap`` over variants,
``jax.lax.scan`` over control ticks) with the flight core's controller, stage
machine, wind and energy model written in ``jax.numpy``.

- ``params.py`` (numpy only): what the batched path supports (a ``ConfigError``
  names anything else) and each variant's numbers, taken from the core's own
  objects (``CascadedController``, ``Meter``, the blueprint's MuJoCo model), so
  the gains and coefficients are the core's, not a copy of its formulas;
- ``control.py``: legs, pilots, stage machine and the cascaded controller;
- ``energy.py``: body drag, Dryden wind, the motor / battery / radio energy
  model and the flight book;
- ``engine.py``: MJX models and data, the scanned tick, the chunked run and
  the KPIs of each variant.

``control``, ``energy`` and ``engine`` import JAX (``pip install
'pytest-flockai[mjx]'``); this package and ``params`` do not.
"""
