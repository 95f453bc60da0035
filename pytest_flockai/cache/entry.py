"""The framing of a cache entry (flights and memoised values alike): a magic line,
one JSON line (the key, the payload's size and SHA-256) and the payload, an .npz
holding arrays and a JSON header, loaded with ``allow_pickle=False`` (no code runs
on read). Anything but a whole, unmodified entry filed under the key asked for
raises ``CorruptEntry``: the caller computes the value again and rewrites it.
"""

from __future__ import annotations

import hashlib
import io
import json
from pathlib import Path

import numpy as np

MAGIC = b"pytest-flockai-flight-cache/2\n"


class CorruptEntry(Exception):
    """A cache entry that must not be trusted (the message says why)."""



def read_entry(p: Path) -> bytes | None:
    """An entry's bytes; None when there is none, CorruptEntry when it cannot be read."""
    try:
        return p.read_bytes()
    except (FileNotFoundError, NotADirectoryError):
        return None
    except OSError as exc:
        raise CorruptEntry(f"cannot read {p}: {exc}") from None


def seal(key: str, arrays: dict, header, magic: bytes = MAGIC) -> bytes:
    """``magic``, a JSON line (key, size and SHA-256 of the payload), the payload: an
    .npz of ``arrays`` and ``header`` (JSON)."""
    arrays = dict(arrays)
    arrays["header"] = np.frombuffer(json.dumps(header).encode(), dtype=np.uint8)
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    payload = buf.getvalue()
    meta = {"key": key, "size": len(payload), "sha256": hashlib.sha256(payload).hexdigest()}
    return magic + json.dumps(meta).encode() + b"\n" + payload


def unseal(data: bytes, key: str, magic: bytes = MAGIC) -> tuple[dict, dict]:
    """(header, arrays) of a sealed entry; CorruptEntry unless it is whole, unmodified
    and filed under ``key`` (the .npz is loaded without pickle: no code runs)."""
    if not data.startswith(magic):
        raise CorruptEntry("not a cache entry of this format (bad magic)")
    rest = data[len(magic):]
    nl = rest.find(b"\n")
    try:
        meta = json.loads(rest[:nl]) if nl > 0 else None
    except ValueError:
        meta = None
    if not isinstance(meta, dict):
        raise CorruptEntry("unreadable entry header")
    payload = rest[nl + 1:]
    if meta.get("key") != key:
        raise CorruptEntry(f"entry is for key {str(meta.get('key'))[:12]}..., not {key[:12]}...")
    if meta.get("size") != len(payload):
        raise CorruptEntry(f"truncated: {len(payload)} of {meta.get('size')} bytes")
    if meta.get("sha256") != hashlib.sha256(payload).hexdigest():
        raise CorruptEntry("payload hash mismatch (the entry was modified)")
    try:
        with np.load(io.BytesIO(payload), allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
        return json.loads(arrays.pop("header").tobytes().decode()), arrays
    except Exception as exc:   # a well-hashed but malformed payload: still never trusted
        raise CorruptEntry(f"malformed payload ({type(exc).__name__}: {exc})") from None


__all__ = ["CorruptEntry", "MAGIC", "read_entry", "seal", "unseal"]
