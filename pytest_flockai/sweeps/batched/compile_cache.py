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

import os
from pathlib import Path

import jax

ENV = "FLOCKAI_JAX_CACHE"


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
    current = jax.config.jax_compilation_cache_dir
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
