"""JAX's persistent compilation cache for the batched backend: a compiled chunk is
written to disk once per machine and read back by every later sweep and process
with the same batch structure and size (XLA compiles take 10-100 s on a CPU).

The folder is ``$FLOCKAI_JAX_CACHE`` if set (an empty value turns the cache off),
else ``$XDG_CACHE_HOME/pytest-flockai/jax`` (``~/.cache/pytest-flockai/jax``). A
cache folder the user has already given JAX (``jax_compilation_cache_dir``) is
left as it is; otherwise the setting is JAX's, for the whole process (other JAX code
in it that compiles for more than a second is cached there too).
"""

from __future__ import annotations

import functools
import os
from pathlib import Path

import jax

ENV = "FLOCKAI_JAX_CACHE"
#: XLA options of the batch's programs on a CPU: XLA's CPU fusion emitters generate code
#: that depends on the batch's size (an element can round differently in a batch of 16 and
#: one of 32), which would make the rows depend on the shard count (``shards.py``); the
#: classic emitters do not. No YNNPACK fusions: each is a library call whose set-up costs
#: more than the few thousand numbers it computes here (the batch's CPU time 1.39 -> 1.05 s,
#: 1,024 Crazyflies x 7.5 s, ``docs/explanation/batched-backend.md``; rows move by an ulp)
CPU_OPTIONS: dict = {"xla_cpu_use_fusion_emitters": False,
                     "xla_cpu_experimental_ynn_fusion_type": ""}


def folder() -> Path | None:
    """The cache folder the backend uses (None: turned off with an empty ``$FLOCKAI_JAX_CACHE``)."""
    given = os.environ.get(ENV)
    if given is not None:
        return Path(given).expanduser() if given.strip() else None
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "pytest-flockai" / "jax"


def enable() -> Path | None:
    """Point JAX's persistent compilation cache at ``folder()`` unless one is set already;
    returns the folder in use."""
    current = jax.config.jax_compilation_cache_dir  # type: ignore[attr-defined]  # options are set at runtime; jax's stub omits them
    if current:
        return Path(current)
    path = folder()
    if path is None:
        return None
    path.mkdir(parents=True, exist_ok=True)
    jax.config.update("jax_compilation_cache_dir", str(path))
    # the chunks take seconds to minutes to compile; the small helpers (reductions, the
    # final step) well under a second: only the former are worth a file
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 1.0)
    return path


@functools.lru_cache(maxsize=2)
def options(cpu: bool = True) -> dict:
    """``CPU_OPTIONS`` on a CPU (nothing elsewhere), less those this JAX does not know (an
    older XLA refuses an unknown option: a one-line program compiled with each tells)."""
    if not cpu:
        return {}
    known = {}
    for name, value in CPU_OPTIONS.items():
        try:
            jax.jit(lambda x: x + 1, compiler_options={name: value}).lower(1.0).compile()
        except Exception:   # noqa: BLE001 - XLA's error for an option it lacks
            continue
        known[name] = value
    return known
