"""The framing of a cache entry (flights and memoised values alike): a magic line,
one JSON line (the key, the payload's size, its SHA-256 and an HMAC-SHA256 with the
cache's secret key, see ``auth.py``) and the payload, an .npz holding arrays and a
JSON header, read with ``allow_pickle=False`` (no code runs on read).

Reading is bounded: the entry is opened without following a symlink and without
blocking (a FIFO or a device is refused, only a regular file is read), its size is
checked before a byte is read (``limits.MAX_CACHE_ENTRY_BYTES``) and the arrays'
declared sizes before anything is decompressed (``limits.MAX_CACHE_UNPACKED_BYTES``).
Anything but a whole, authentic entry filed under the key asked for raises
``CorruptEntry`` (``NotAuthentic`` for a bad or missing HMAC): the caller computes
the value again and rewrites it.
"""

from __future__ import annotations

import errno
import hashlib
import io
import json
import os
import stat
import zipfile
from pathlib import Path

import numpy as np

from .. import limits
from .auth import CacheKey

MAGIC = b"pytest-flockai-flight-cache/3\n"
#: the first line of a memoised value's entry (``memo_store.py``)
MEMO_MAGIC = b"pytest-flockai-memo/1\n"
_MAX_MEMBERS = 100_000


class CorruptEntry(Exception):
    """A cache entry that must not be trusted (the message says why)."""


class NotAFile(CorruptEntry):
    """Something else than a regular file at an entry's path (a folder, a FIFO, a
    device, a symlink): a corrupt entry, flown again; the run warns once."""


class NotAuthentic(CorruptEntry):
    """A cache entry not sealed with this cache's key (forged, another key, or none)."""


def read_entry(p: Path) -> bytes | None:
    """An entry's bytes; None when there is none, CorruptEntry when it is not a regular
    file, too big, or cannot be read. Never blocks, never follows a symlink."""
    try:
        fd = os.open(p, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC)
    except (FileNotFoundError, NotADirectoryError):
        return None
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            raise NotAFile(f"cannot read {p}: a symlink") from None
        raise CorruptEntry(f"cannot read {p}: {exc.strerror or exc}") from None
    st = os.fstat(fd)
    if not stat.S_ISREG(st.st_mode):
        os.close(fd)                       # a folder's fd cannot even be wrapped (fdopen)
        what = "a folder" if stat.S_ISDIR(st.st_mode) else "a FIFO, a device or a socket"
        raise NotAFile(f"{p} is not a regular file ({what})")
    with os.fdopen(fd, "rb") as fh:
        if st.st_size > limits.MAX_CACHE_ENTRY_BYTES:
            raise CorruptEntry(f"{p} is {st.st_size} bytes, above "
                               f"pytest_flockai.limits.MAX_CACHE_ENTRY_BYTES = "
                               f"{limits.MAX_CACHE_ENTRY_BYTES}")
        try:
            data = fh.read(st.st_size + 1)
        except OSError as exc:
            raise CorruptEntry(f"cannot read {p}: {exc.strerror or exc}") from None
    if len(data) > st.st_size:
        raise CorruptEntry(f"{p} grew while it was read")
    return data


def seal(key: str, arrays: dict, header: object, secret: CacheKey,
         magic: bytes = MAGIC) -> bytes:
    """``magic``, a JSON line (key, size, SHA-256 and HMAC of the payload), the payload:
    an .npz of ``arrays`` and ``header`` (JSON)."""
    arrays = dict(arrays)
    arrays["header"] = np.frombuffer(json.dumps(header).encode(), dtype=np.uint8)
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    payload = buf.getvalue()
    digest = hashlib.sha256(payload).hexdigest()
    meta = {"key": key, "size": len(payload), "sha256": digest,
            "hmac": secret.mac(magic, key.encode(), digest.encode())}
    return magic + json.dumps(meta).encode() + b"\n" + payload


def unseal(data: bytes, key: str, secret: CacheKey, magic: bytes = MAGIC) -> tuple[dict, dict]:
    """(header, arrays) of a sealed entry; CorruptEntry unless it is whole, authentic
    and filed under ``key`` (the .npz is read without pickle, within the limits)."""
    if not data.startswith(magic):
        raise CorruptEntry("not a cache entry of this format (bad magic)")
    rest = data[len(magic):]
    nl = rest.find(b"\n", 0, 4096)
    try:
        meta = json.loads(rest[:nl]) if nl > 0 else None
    except (ValueError, RecursionError):
        meta = None
    if not isinstance(meta, dict):
        raise CorruptEntry("unreadable entry header")
    payload = rest[nl + 1:]
    if meta.get("key") != key:
        raise CorruptEntry(f"entry is for key {str(meta.get('key'))[:12]}..., not {key[:12]}...")
    if meta.get("size") != len(payload):
        raise CorruptEntry(f"truncated: {len(payload)} of {meta.get('size')} bytes")
    digest = hashlib.sha256(payload).hexdigest()
    if meta.get("sha256") != digest:
        raise CorruptEntry("payload hash mismatch (the entry was modified)")
    if not secret.verify(meta.get("hmac"), magic, key.encode(), digest.encode()):
        raise NotAuthentic(f"cache entry not authentic (not sealed with the key from "
                           f"{secret.source}: forged, or written under another key or none)")
    try:
        arrays = load_npz(payload)
        return json.loads(arrays.pop("header").tobytes().decode()), arrays
    except CorruptEntry:
        raise
    except Exception as exc:  # noqa: BLE001 (authentic but malformed: never trusted)
        raise CorruptEntry(f"malformed payload ({type(exc).__name__}: {exc})") from None


def load_npz(payload: bytes) -> dict:
    """The arrays of an .npz, each member's declared size checked before it is
    decompressed and each array's shape checked against its bytes (no pickle)."""
    with zipfile.ZipFile(io.BytesIO(payload)) as zf:
        infos = zf.infolist()
        if len(infos) > _MAX_MEMBERS:
            raise CorruptEntry(f"{len(infos)} arrays in one entry")
        total = sum(i.file_size for i in infos)
        if total > limits.MAX_CACHE_UNPACKED_BYTES:
            raise CorruptEntry(f"the entry declares {total} bytes unpacked, above "
                               f"pytest_flockai.limits.MAX_CACHE_UNPACKED_BYTES = "
                               f"{limits.MAX_CACHE_UNPACKED_BYTES}")
        out = {}
        for info in infos:
            with zf.open(info) as fh:
                raw = fh.read(info.file_size + 1)
            name = info.filename.removesuffix(".npy")
            out[name] = _array(raw, info.filename)
        return out


def _array(raw: bytes, name: str) -> np.ndarray:
    fp = io.BytesIO(raw)
    version = np.lib.format.read_magic(fp)
    if version == (1, 0):
        shape, fortran, dtype = np.lib.format.read_array_header_1_0(fp)
    elif version == (2, 0):
        shape, fortran, dtype = np.lib.format.read_array_header_2_0(fp)
    else:
        raise CorruptEntry(f"array {name}: .npy version {version} is not read")
    if dtype.hasobject:
        raise CorruptEntry(f"array {name}: object arrays are never read (pickle)")
    count = int(np.prod(shape, dtype=np.int64)) if shape else 1
    start = fp.tell()
    if count < 0 or count * dtype.itemsize != len(raw) - start:
        raise CorruptEntry(f"array {name}: shape {shape} does not match its "
                           f"{len(raw) - start} bytes")
    arr = np.frombuffer(raw, dtype=dtype, count=count, offset=start)
    return arr.reshape(shape[::-1]).T.copy() if fortran else arr.reshape(shape).copy()


__all__ = ["MAGIC", "MEMO_MAGIC", "CorruptEntry", "NotAFile", "NotAuthentic", "load_npz", "read_entry", "seal", "unseal"]
