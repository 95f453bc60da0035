"""The ``Unit`` and ``Device`` records (``compute.devices`` explains them)."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field, replace

from ..errors import ConfigError


@dataclass(frozen=True)
class Unit:
    """A compute unit of a computer: ``kind`` (cpu/gpu/npu), ``cores`` (CPU cores, or 1),
    ``clock_ghz`` and ``peak``: ((precision, peak MAC/s of the whole unit), ...); for an
    accelerator that keeps the network's parameters in its own memory (the Edge TPU),
    ``cache_mb`` of it and ``link_gbs``, the host link the parameters that do not fit stream
    over at every inference (0: neither)."""

    kind: str
    cores: int
    clock_ghz: float
    peak: tuple[tuple[str, float], ...]
    name: str = ""
    tensor_cores: int = 0
    cache_mb: float = 0.0
    link_gbs: float = 0.0

    @property
    def precisions(self) -> tuple[str, ...]:
        return tuple(p for p, _ in self.peak)

    def peak_macs(self, precision: str, threads: int | None = None) -> float:
        """Peak MAC/s at ``precision`` with ``threads`` of the unit's cores (None: all)."""
        v = dict(self.peak)[precision]
        if threads is not None and self.cores > 1:
            v *= min(threads, self.cores) / self.cores
        return v


@dataclass(frozen=True)
class Device:
    """A computer: power (W, at the board's input), the MAC-count rule's throughput (MAC/s)
    and per-inference overhead (s), memory (MB), sources, and its datasheet (units,
    memory bandwidth in GB/s, runtime/target pairs, power mode)."""

    name: str
    idle_w: float
    active_w: float
    macs_per_s: float
    overhead_s: float
    memory_mb: float
    source: str
    units: tuple[Unit, ...] = ()
    bandwidth_gbs: float = 0.0
    #: sustained (STREAM) memory bandwidth measured on the board, GB/s; 0: none published
    stream_gbs: float = 0.0
    deployments: tuple[str, ...] = ()
    mode: str = ""
    #: the default (runtime, precision, target, threads) a drone's blueprint sets for its tasks
    defaults: tuple[tuple[str, object], ...] = ()
    sources: tuple[tuple[str, str], ...] = field(default=(), compare=False)
    #: a measured profile (``compute.profile``) whose samples give the inference latencies
    measured: object = field(default=None, compare=False, repr=False)

    def unit(self, kind: str) -> Unit:
        """The unit of ``kind`` (cpu/gpu/npu); ConfigError when the computer has none."""
        for u in self.units:
            if u.kind == kind:
                return u
        raise ConfigError(f"target = {kind!r} is not available on computer {self.name!r}; "
                          f"allowed: {', '.join(u.kind for u in self.units) or 'none'}")

    @property
    def runtimes(self) -> tuple[str, ...]:
        """The runtimes this computer can run (first: the default)."""
        return tuple(dict.fromkeys(d.split("/")[0] for d in self.deployments))

    def to_dict(self) -> dict:
        """The fields as a JSON-ready dict."""
        out = asdict(replace(self, measured=None))
        out["measured"] = getattr(self.measured, "path", None) if self.measured else None
        return out


__all__ = ["Device", "Unit"]
