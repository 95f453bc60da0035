"""The batch split over the CPUs the process may use.

One XLA thread runs the batch fastest per CPU-second (``cpu_threads.py``), but a
machine with several cores then leaves all but one idle. So on a CPU the batch is
split into shards, one per CPU in ``os.sched_getaffinity``, each an XLA host device
(``--xla_force_host_platform_device_count``, set before JAX's CPU client starts) that
runs its shard on its own thread: one program (``jax.shard_map`` over the variants'
axis), compiled once, each shard with its own batch-level conditions, no
communication between shards. Host devices in one process measured faster than
worker processes here (no second JAX start, no compile or cache load per process, no
copies of the variants' numbers).

``$FLOCKAI_JAX_CPU_SHARDS`` overrides the count: a whole number >= 1 (``1``: the
unsharded batch); empty or unset: one per CPU. Variants are independent (no reduction
across the batch), so the rows are the same bit for bit whatever the count
(``tests/sweeps/test_batched_shards.py``). On a GPU, and when JAX's client was started
before with fewer CPU devices, fewer shards run; ``df.attrs["jax_cpu_shards"]`` says
how many did.
"""

from __future__ import annotations

import os

from ...errors import ConfigError

ENV = "FLOCKAI_JAX_CPU_SHARDS"
FLAG = "--xla_force_host_platform_device_count"


def cpus() -> int:
    """The CPUs this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:                  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def wanted() -> int:
    """``$FLOCKAI_JAX_CPU_SHARDS`` (default: one shard per CPU); a ConfigError naming the
    variable for anything but a whole number >= 1."""
    raw = os.environ.get(ENV, "").strip()
    if not raw:
        return cpus()
    try:
        value = int(raw)
    except ValueError:
        value = 0
    if value < 1 or str(value) != raw.lstrip("+"):
        raise ConfigError(f"${ENV} = {raw!r} is not allowed; allowed: a whole number >= 1 "
                          f"(shards of the batch, one XLA host device each), or unset for "
                          f"one per CPU ({cpus()} here)")
    return value


def prepare(device: str | None) -> None:
    """Before JAX's client starts: as many XLA host devices as shards wanted (a count
    already in ``$XLA_FLAGS`` is kept). Nothing on another device."""
    if device not in (None, "cpu"):
        return
    n = wanted()
    flags = os.environ.get("XLA_FLAGS", "")
    if n > 1 and FLAG not in flags:
        os.environ["XLA_FLAGS"] = f"{flags} {FLAG}={n}".strip()


def count(device: str | None) -> int:
    """Shards this batch runs in: ``wanted()`` on the CPU devices JAX has (1 on another
    device, or where JAX's default backend is not the CPU)."""
    import jax
    if device not in (None, "cpu") or (device is None and jax.default_backend() != "cpu"):
        return 1
    return max(1, min(wanted(), len(jax.devices("cpu"))))
