"""The flight cache's folder as a whole: its size, least-recently-used eviction and
what ``flockai cache info``/``prune`` print.

A hit touches its entry's modification time, so "least recently used" is the oldest
modification time. After a write, when the folder holds more than ``max_bytes``
(``limits.MAX_CACHE_BYTES`` unless given), the least recently used entries (flights
and memoised values alike) are removed until it holds at most 90 % of it. Only
regular files named like entries are counted or removed; nothing is followed
through a symlink.
"""

from __future__ import annotations

import os
import stat
import time
from dataclasses import dataclass
from pathlib import Path

#: what eviction leaves, as a fraction of the limit (room for the next writes)
LOW_WATER = 0.9
_SUFFIXES = (".flight", ".memo")


@dataclass
class Entry:
    path: Path
    size: int
    mtime: float


def scan(directory) -> list[Entry]:
    """Every entry file under ``directory`` (flights in ``xx/``, memo values in
    ``memo/xx/``), oldest use first."""
    out: list[Entry] = []
    for root in (Path(directory), Path(directory) / "memo"):
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
        if stat.S_ISREG(st.st_mode):
            out.append(Entry(Path(d.path), st.st_size, st.st_mtime))
    return out


def clear_for_write(path: Path) -> None:
    """Remove whatever is at an entry's path unless it is a regular file (a FIFO, a
    device node, a link planted there): the new entry is renamed into its place."""
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return
    if not stat.S_ISREG(st.st_mode):
        if stat.S_ISDIR(st.st_mode):
            os.rmdir(path)                        # an empty one; else the write fails
        else:
            os.unlink(path)


def touch(path: Path) -> None:
    """Mark an entry used now (its mtime; a read-only cache folder is left as it is)."""
    try:
        os.utime(path, follow_symlinks=False)
    except (OSError, NotImplementedError):
        pass


def prune(directory, max_bytes: int, *, older_than_s: float | None = None,
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


def info(directory) -> dict:
    """Entries, bytes, and the oldest and newest use, of a cache folder."""
    found = scan(directory)
    flights = [e for e in found if e.path.suffix == ".flight"]
    return {"directory": str(directory), "entries": len(found), "flights": len(flights),
            "memo": len(found) - len(flights), "bytes": sum(e.size for e in found),
            "oldest_use": found[0].mtime if found else None,
            "newest_use": found[-1].mtime if found else None}


__all__ = ["LOW_WATER", "Entry", "clear_for_write", "info", "prune", "scan", "touch"]
