"""Hostile flight-cache entries (issue 28): how long the cache takes to refuse each,
and how much memory that costs.

Each case runs in a fresh Python process that imports the package, opens a cache
whose one entry is hostile, and looks the flight up; the figures are the lookup's
wall time, the ``tracemalloc`` peak during it and the process' peak resident set
size (``getrusage``, C allocations included) above what it held before the lookup.
Cases: a FIFO (before: blocked pytest forever), a symlink to /dev/zero (before:
read without bound), a 2 GiB "zip bomb" sealed with the right key (before: 2.3 GB
of memory before it was refused) and the same bomb with a forged HMAC.

    python benchmarks/cache_hostile.py
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile

CHILD = r"""
import json, os, resource, sys, time, tracemalloc
import pytest_flockai as fa
from pytest_flockai.cache import FlightCache, CorruptEntry
cache = FlightCache(sys.argv[1])
key = sys.argv[2]
rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
tracemalloc.start()
t0 = time.perf_counter()
try:
    cache.get(key)
    why = "ACCEPTED"
except CorruptEntry as exc:
    why = str(exc)
dt = time.perf_counter() - t0
peak = tracemalloc.get_traced_memory()[1]
rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(json.dumps({"s": dt, "py_peak_mb": peak / 2**20, "rss_growth_mb": (rss1 - rss0) / 1024,
                  "why": why}))
"""


def _bomb(declared: int) -> bytes:
    """An .npz whose one array declares ``declared`` bytes of zeros, really compressed."""
    import io
    import zipfile

    import numpy as np
    head = io.BytesIO()
    np.lib.format.write_array_header_1_0(head, {"descr": "|u1", "fortran_order": False,
                                                "shape": (declared,)})
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as zf:
        with zf.open("header.npy", "w", force_zip64=True) as fh:
            fh.write(head.getvalue())
            chunk = bytes(8 * 2**20)
            for _ in range(declared // len(chunk)):
                fh.write(chunk)
    return buf.getvalue()


def _sealed(payload: bytes, key: str, secret, forge: bool) -> bytes:
    import hashlib

    from pytest_flockai.cache.entry import MAGIC
    digest = hashlib.sha256(payload).hexdigest()
    mac = "0" * 64 if forge else secret.mac(MAGIC, key.encode(), digest.encode())
    meta = {"key": key, "size": len(payload), "sha256": digest, "hmac": mac}
    return MAGIC + json.dumps(meta).encode() + b"\n" + payload


def main() -> None:
    from pytest_flockai.cache import FlightCache
    key = "ab" * 32
    bomb = _bomb(2 * 2**30)
    print(f"load average: {open('/proc/loadavg').read().split()[:3]}")
    print(f"bomb: {len(bomb) / 2**20:.1f} MiB compressed, declares 2048 MiB")
    cases = {
        "fifo": lambda p, s: os.mkfifo(p),
        "symlink to /dev/zero": lambda p, s: os.symlink("/dev/zero", p),
        "2 GiB bomb, right key": lambda p, s: p.write_bytes(_sealed(bomb, key, s, False)),
        "2 GiB bomb, forged HMAC": lambda p, s: p.write_bytes(_sealed(bomb, key, s, True)),
    }
    for name, make in cases.items():
        with tempfile.TemporaryDirectory() as d:
            cache = FlightCache(d)
            p = cache.path(key)
            p.parent.mkdir(parents=True)
            make(p, cache.key)
            out = subprocess.run([sys.executable, "-c", CHILD, d, key], capture_output=True,
                                 text=True, timeout=120)
            if out.returncode:
                print(f"{name:26s} FAILED: {out.stderr.strip()[-300:]}")
                continue
            r = json.loads(out.stdout.strip().splitlines()[-1])
            print(f"{name:26s} refused in {r['s'] * 1e3:7.2f} ms, Python peak "
                  f"{r['py_peak_mb']:6.1f} MiB, RSS growth {r['rss_growth_mb']:6.1f} MiB: "
                  f"{r['why'].replace(d, '<dir>')[:90]}")


if __name__ == "__main__":
    main()
