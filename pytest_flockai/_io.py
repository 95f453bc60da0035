"""Atomic file writes: a temporary file in the same folder, flushed, then renamed.

The file gets the mode any new file of this process gets (0666 less the
umask), not the 0600 of the temporary file it was written as. Only a regular
file is ever replaced: a folder, a device (``/dev/full``), a FIFO or a socket at
``path`` is refused, as is a missing folder; any failure (a full disk, a
read-only folder) raises ``WriteError`` naming ``path`` (never the temporary
file), and leaves the old file as it was and no temporary file behind.

Also two helpers for what is read and printed: ``json_depth`` (nesting, counted
without recursion) and ``printable`` (control characters escaped for a terminal).
"""

from __future__ import annotations

import functools
import hashlib
import os
import stat
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import IO, Any

from .errors import WriteError


def _umask() -> int:
    """The process' umask (os.umask sets it; set it straight back)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _failed(path: str | os.PathLike, exc: OSError) -> WriteError:
    err = WriteError(f"cannot write {str(path)!r}: {exc.strerror or exc}")
    err.errno = exc.errno
    return err


def check_target(path: str | os.PathLike) -> Path:
    """``path`` as a Path; WriteError unless a regular file may be put there (its
    folder exists; nothing but a regular file, or a link to one, is there now)."""
    path = Path(path)
    try:
        st = os.stat(path)
    except FileNotFoundError:
        st = None
    except OSError as exc:
        raise _failed(path, exc) from None
    if st is not None and stat.S_ISDIR(st.st_mode):
        raise WriteError(f"cannot write {str(path)!r}: it is a folder; give a file path")
    if st is not None and not stat.S_ISREG(st.st_mode):
        raise WriteError(f"cannot write {str(path)!r}: it is a device, a FIFO or a socket, "
                         f"which would be replaced; give the path of a regular file")
    if not path.parent.is_dir():
        raise WriteError(f"cannot write {str(path)!r}: folder {str(path.parent)!r} does not "
                         f"exist")
    return path


def atomic_write(path: str | os.PathLike, write: Callable[[IO[Any]], object], *,
                 text: bool = True) -> Path:
    """Call ``write(fh)`` on a temporary file next to ``path``, then ``os.replace`` it."""
    path = check_target(path)
    try:
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    except OSError as exc:
        raise _failed(path, exc) from None
    try:
        with os.fdopen(fd, "w", encoding="utf-8") if text else os.fdopen(fd, "wb") as fh:
            os.fchmod(fh.fileno(), 0o666 & ~_umask())
            write(fh)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException as exc:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        if isinstance(exc, OSError) and not isinstance(exc, WriteError):
            raise _failed(path, exc) from None
        raise
    return path


def replace_from(tmp: str | os.PathLike, path: str | os.PathLike) -> Path:
    """Move a finished temporary file ``tmp`` over ``path`` (checked like
    ``atomic_write``); ``tmp`` is removed when that fails."""
    try:
        check_target(path)
        os.replace(tmp, path)
    except OSError as exc:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        if isinstance(exc, WriteError):
            raise
        raise _failed(path, exc) from None
    return Path(path)


def json_depth(data: object, stop: int = 1 << 30) -> int:
    """How deeply lists and dicts nest in ``data`` (0 for a plain value), counted
    without recursion and not past ``stop`` + 1."""
    deepest, stack = 0, [(data, 1)]
    while stack:
        obj, d = stack.pop()
        if isinstance(obj, dict):
            obj = list(obj.values())
        if isinstance(obj, list):
            deepest = max(deepest, d)
            if d <= stop:
                stack.extend((v, d + 1) for v in obj if isinstance(v, (dict, list)))
    return deepest


_CONTROL = {c: f"\\x{c:02x}" for c in [*range(0x00, 0x20), *range(0x7f, 0xa0)]}
_CONTROL_KEEP_NL = {c: v for c, v in _CONTROL.items() if c != 0x0a}


def printable(text: object, *, newlines: bool = False) -> str:
    """``text`` with control characters (ANSI escapes, carriage returns, ...) shown as
    ``\\xNN``, safe to print on a terminal; ``newlines`` keeps line breaks."""
    return str(text).translate(_CONTROL_KEEP_NL if newlines else _CONTROL)


def sha256_of(path: str | os.PathLike) -> str:
    """SHA-256 of a file's bytes, read in 1 MiB blocks."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


@functools.lru_cache(maxsize=256)
def _sha256_memo(path: str, ino: int, mtime_ns: int, ctime_ns: int, size: int) -> str:
    return sha256_of(path)


def file_digest(path: str | os.PathLike) -> str:
    """SHA-256 of a file's bytes, memoised on its path, inode, mtime, ctime and size (model
    files, blueprints: read once per process unless they change). The ctime counts: a file
    rewritten with the same size and its old mtime put back (``cp -p``, ``os.utime``) has
    a new ctime, which no user call can set."""
    st = os.stat(path)
    return _sha256_memo(os.fspath(path), st.st_ino, st.st_mtime_ns, st.st_ctime_ns, st.st_size)
