"""The flight cache's folder as a whole: its size, least-recently-used eviction and
what ``flockai cache info``/``prune`` print.

A hit touches its entry's modification time, so "least recently used" is the oldest
modification time. After a write, when the folder holds more than ``max_bytes``
(``limits.MAX_CACHE_BYTES`` unless given), the least recently used entries (flights
and memoised values alike) are removed until it holds at most 90 % of it. Only
regular files named like entries *and starting with the cache's own header* (the
magic line of a flight or a memo entry) are counted, pruned or cleared: a user's
``db/schema.flight`` in a folder wrongly given to ``flockai cache prune`` stays.
Nothing is followed through a symlink: a shard folder (``ab/``, ``memo/``) that is
a symlink is neither scanned nor written through (``unsafe_parent``).
"""

from __future__ import annotations

import os
import stat
import time
from dataclasses import dataclass
from pathlib import Path

from .entry import MAGIC, MEMO_MAGIC

#: what eviction leaves, as a fraction of the limit (room for the next writes)
LOW_WATER = 0.9
_SUFFIXES = (".flight", ".memo")
_HEADERS = {".flight": MAGIC, ".memo": MEMO_MAGIC}


@dataclass
class Entry:
    """One entry file: its path, size (bytes) and last use (mtime, s)."""

    path: Path
    size: int
    mtime: float


def scan(directory: str | os.PathLike) -> list[Entry]:
    """Every entry file under ``directory`` (flights in ``xx/``, memo values in
    ``memo/xx/``), oldest use first."""
    out: list[Entry] = []
    roots = [Path(directory)]
    if _real_dir(Path(directory) / "memo"):
        roots.append(Path(directory) / "memo")
    for root in roots:
        for sub in _dirs(root):
            out.extend(_files(sub))
    out.sort(key=lambda e: (e.mtime, str(e.path)))
    return out


def _dirs(root: Path):
    try:
        with os.scandir(root) as it:
            return [Path(d.path) for d in it if d.is_dir(follow_symlinks=False)
                    and len(d.name) == 2]
    except OSError:
        return []


def _real_dir(p: Path) -> bool:
    try:
        return stat.S_ISDIR(os.lstat(p).st_mode)
    except OSError:
        return False


def has_header(path: Path) -> bool:
    """Whether ``path`` is a regular file starting with the cache's own magic line for
    its suffix (read without following a symlink, without blocking)."""
    magic = _HEADERS.get(path.suffix)
    if magic is None:
        return False
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC)
    except OSError:
        return False
    try:
        return stat.S_ISREG(os.fstat(fd).st_mode) and os.read(fd, len(magic)) == magic
    except OSError:
        return False
    finally:
        os.close(fd)


def unsafe_parent(root: Path, path: Path) -> str | None:
    """Why ``path``'s folders under ``root`` must not be used (one is a symlink or not a
    folder: a write would land wherever it points), or None (missing ones are made)."""
    try:
        parts = path.parent.relative_to(root).parts
    except ValueError:
        return f"{path} is not under the cache folder {root}"
    cur = root
    for part in parts:
        cur = cur / part
        try:
            st = os.lstat(cur)
        except OSError:          # missing, or the root unreachable: the write reports it
            return None
        if stat.S_ISLNK(st.st_mode):
            return f"{cur} is a symlink (never written or read through)"
        if not stat.S_ISDIR(st.st_mode):
            return f"{cur} is not a folder"
    return None


def _files(folder: Path):
    try:
        with os.scandir(folder) as it:
            items = [d for d in it if d.name.endswith(_SUFFIXES)]
    except OSError:
        return []
    out = []
    for d in items:
        try:
            st = d.stat(follow_symlinks=False)
        except OSError:
            continue
        if stat.S_ISREG(st.st_mode) and has_header(Path(d.path)):
            out.append(Entry(Path(d.path), st.st_size, st.st_mtime))
    return out


def clear_for_write(path: Path) -> bool:
    """Remove whatever is at an entry's path unless it is a regular file (a FIFO, a
    device node, a link, an empty folder planted there): the new entry is renamed into
    its place. False for a folder that is not empty (never removed: not ours)."""
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return True
    if not stat.S_ISREG(st.st_mode):
        if stat.S_ISDIR(st.st_mode):
            try:
                os.rmdir(path)                    # only an empty one
            except OSError:
                return False
        else:
            os.unlink(path)
    return True


def touch(path: Path) -> None:
    """Mark an entry used now (its mtime; a read-only cache folder is left as it is)."""
    try:
        os.utime(path, follow_symlinks=False)
    except (OSError, NotImplementedError):
        pass


def prune(directory: str | os.PathLike, max_bytes: int, *, older_than_s: float | None = None,
          low_water: float = LOW_WATER) -> tuple[int, int]:
    """Remove entries unused for ``older_than_s``, then the least recently used until
    the folder holds at most ``low_water * max_bytes`` (nothing when it holds at most
    ``max_bytes``); returns (entries removed, bytes freed)."""
    found = scan(directory)
    total = sum(e.size for e in found)
    removed, freed = 0, 0
    now = time.time()
    target = total if total <= max_bytes else int(low_water * max_bytes)
    for e in found:
        old = older_than_s is not None and now - e.mtime > older_than_s
        if not old and total - freed <= target:
            continue
        try:
            os.unlink(e.path)
        except FileNotFoundError:
            pass
        except OSError:
            continue
        removed += 1
        freed += e.size
    return removed, freed


def clear(directory: str | os.PathLike) -> int:
    """Remove every entry (only files carrying the cache's header) and the shard folders
    left empty; anything else in the folder stays. Returns the entries removed."""
    removed = 0
    for e in scan(directory):
        try:
            os.unlink(e.path)
            removed += 1
        except OSError:
            pass
    root = Path(directory)
    shards = [root / "memo" / d.name for d in _dirs(root / "memo")] \
        if _real_dir(root / "memo") else []
    for folder in [*shards, root / "memo", *_dirs(root)]:
        try:
            os.rmdir(folder)                     # only an empty one
        except OSError:
            pass
    return removed


def info(directory: str | os.PathLike) -> dict:
    """Entries, bytes, and the oldest and newest use, of a cache folder."""
    found = scan(directory)
    flights = [e for e in found if e.path.suffix == ".flight"]
    return {"directory": str(directory), "entries": len(found), "flights": len(flights),
            "memo": len(found) - len(flights), "bytes": sum(e.size for e in found),
            "oldest_use": found[0].mtime if found else None,
            "newest_use": found[-1].mtime if found else None}


__all__ = ["LOW_WATER", "Entry", "clear", "clear_for_write", "has_header", "info", "prune",
           "scan", "touch", "unsafe_parent"]
