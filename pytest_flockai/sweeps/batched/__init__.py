"""The batched sweep backends (``fa.sweep(..., backend="jax" | "mjx")``): every
variant of a sweep in one batch (``jax.vmap`` over variants, ``jax.lax.scan`` over
control ticks) with the flight core's controller, stage machine, wind and energy
model in ``jax.numpy``, on a free-flying rigid body ("jax") or MJX's full physics
("mjx"). docs/explanation/batched-backend.md explains it.

- ``params.py`` (numpy only): what the batched path supports (a ``ConfigError``
  names anything else) and each variant's typed numbers (``VariantParams``),
  exported by the core's own objects (``batch_params()``), built by the flight's
  own factories (``mission/parts.py``);
- ``rigid_model.py`` (numpy only): the free body's numbers, read from the compiled
  MuJoCo model, and whether it can fly that model;
- ``control.py``: legs, pilots, stage machine and the cascaded controller;
- ``energy.py``: body drag, H-force, Dryden wind, the motor / battery / radio
  energy model and the flight book (the battery and wind through the core's own
  ``xp`` formulas);
- ``rigid.py``: MuJoCo's Euler step for the free body, the ground apart;
- ``engine.py``: the batches (buckets), the scanned tick, the chunked run and the
  KPIs of each variant (``rows.py``); ``compile_cache.py``: JAX's persistent cache.

``control``, ``energy``, ``rigid`` and ``engine`` import JAX (``pip install
'pytest-flockai[mjx]'``); this package, ``params`` and ``rigid_model`` do not.
"""
