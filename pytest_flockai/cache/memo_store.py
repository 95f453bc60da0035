"""The memo store of the flight cache: computations memoised through
``pytest_flockai.memo`` (rendered views, detection scores, envelopes), stored in
the flight cache's directory under ``memo/`` with the same checks as a flight
(the entry names its key, its payload's size, SHA-256 and HMAC; an .npz read
without pickle, within the limits), the same modes and the same atomic writes. A truncated, tampered or
unreadable entry is never trusted: the value is computed again and the entry
rewritten. ``counts`` says what happened, per status.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from . import disk as _disk
from . import key as _key
from .entry import MEMO_MAGIC, read_entry, seal, unseal

if TYPE_CHECKING:
    from .store import FlightCache

MAGIC = MEMO_MAGIC


class MemoStore:
    """``recall`` for ``pytest_flockai.memo``, kept in ``cache``'s directory and mode."""

    def __init__(self, cache: FlightCache) -> None:
        self.cache = cache
        self.counts: Counter = Counter()

    def path(self, key: str) -> Path:
        """The file of the entry ``key``."""
        return self.cache.directory / "memo" / key[:2] / f"{key}.memo"

    def recall(self, kind: str, inputs: object, compute: Callable[[], Any],
               pack: Callable[[Any], Any], unpack: Callable[[Any], Any]) -> Any:
        """``compute()``, or the value kept for ``kind`` and ``inputs`` (then counted
        as a hit); a fresh value is stored when the cache's mode writes."""
        cache = self.cache
        if cache.mode == "off":
            return compute()
        try:
            key = _key.memo_key(kind, inputs)
        except _key.Uncacheable:
            self.counts["bypass"] += 1
            return compute()
        status = "stored"
        if cache.reads and _disk.unsafe_parent(cache.directory, self.path(key)) is None:
            try:
                data = read_entry(self.path(key))
                if data is not None:
                    value = unpack(_plain(*unseal(data, key, cache.key, MAGIC)))
                    self.counts["hit"] += 1
                    return value
            except Exception:           # corrupt, or sealed but unusable by unpack(): not trusted
                status = "replaced"
        value = compute()
        self.counts[status if self._put(key, pack, value) else "computed"] += 1
        return value

    def _put(self, key: str, pack, value) -> bool:
        if not self.cache.writes:
            return False
        arrays: dict = {}
        try:
            blob = seal(key, arrays, _header(pack(value), arrays), self.cache.key, MAGIC)
        except (TypeError, ValueError):        # not plain data: computed, not stored
            return False
        if not self.cache.write_entry(self.path(key), blob):
            return False
        self.cache.wrote(len(blob))
        return True


def _header(value, arrays: dict):
    """Plain data with every NumPy array replaced by {"@": name} (the array goes to ``arrays``)."""
    if isinstance(value, np.ndarray):
        name = f"a{len(arrays)}"
        arrays[name] = value
        return {"@": name}
    if isinstance(value, dict):
        return {"{}": [[k, _header(v, arrays)] for k, v in value.items()]}
    if isinstance(value, (list, tuple)):
        return [_header(v, arrays) for v in value]
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    raise TypeError(f"memo values are plain data and NumPy arrays, not {type(value).__name__}")


def _plain(header, arrays: dict):
    if isinstance(header, dict):
        if "@" in header:
            return arrays[header["@"]]
        return {k: _plain(v, arrays) for k, v in header["{}"]}
    if isinstance(header, list):
        return [_plain(v, arrays) for v in header]
    return header


__all__ = ["MAGIC", "MemoStore"]
