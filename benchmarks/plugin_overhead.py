"""What the pytest plugin costs a run that flies nothing: a one-test pytest run
with the plugin (as installed: the ``pytest11`` entry point ``flockai``) against
the same run with ``-p no:flockai``.

Runs ``python -m pytest -q -p no:cacheprovider test_one.py`` in a fresh process,
alternating the two forms (--repeat times each), and prints the median wall
time and CPU time (user + system, less sensitive to other jobs on a shared
machine) of each and their differences, beside the load average. Then, in one more
run with the plugin, lists which heavy libraries the run imported (none is the
goal: MuJoCo, pandas, NumPy, ONNX Runtime and OpenCV load on a flight's first use).

    python benchmarks/plugin_overhead.py [--repeat 15]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

TEST = "def test_one():\n    assert 1 + 1 == 2\n"
HEAVY = ("mujoco", "pandas", "numpy", "onnxruntime", "cv2", "scipy", "matplotlib")
PROBE = ("import sys, pytest\n"
         "rc = pytest.main(['-q', '-p', 'no:cacheprovider', 'test_one.py'])\n"
         "print('HEAVY', ' '.join(m for m in {heavy!r} if m in sys.modules))\n")


def run(folder: Path, extra: list) -> tuple[float, float]:
    """(wall s, CPU s: user + system of the pytest process) of one run."""
    t0 = time.perf_counter()
    p = subprocess.Popen([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *extra,
                          "test_one.py"], cwd=folder, stdout=subprocess.DEVNULL,
                         stderr=subprocess.DEVNULL)
    _, status, usage = os.wait4(p.pid, 0)
    p.returncode = os.waitstatus_to_exitcode(status)
    if p.returncode != 0:
        raise RuntimeError(f"pytest {' '.join(extra)} exited with {p.returncode}")
    return time.perf_counter() - t0, usage.ru_utime + usage.ru_stime


def heavy_imports(folder: Path) -> str:
    out = subprocess.run([sys.executable, "-c", PROBE.format(heavy=HEAVY)], cwd=folder,
                         check=True, capture_output=True, text=True).stdout
    line = next(x for x in out.splitlines() if x.startswith("HEAVY"))
    return line[len("HEAVY"):].strip() or "none"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=15)
    a = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        (folder / "test_one.py").write_text(TEST)
        run(folder, [])                                   # warm the file system caches
        load0 = os.getloadavg()[0]
        on, off = [], []
        for _ in range(a.repeat):                         # interleaved: the same load for both
            on.append(run(folder, []))
            off.append(run(folder, ["-p", "no:flockai"]))
        heavy = heavy_imports(folder)
    print(f"plugin overhead: one trivial test, median of {a.repeat} interleaved runs each; "
          f"load average {load0:.2f} -> {os.getloadavg()[0]:.2f} on {os.cpu_count()} CPUs")
    print(f"{'':26s} {'wall s':>8s} {'CPU s':>8s}")
    med = [[statistics.median(x[k] for x in runs) for k in (0, 1)] for runs in (on, off)]
    print(f"{'with the plugin':26s} {med[0][0]:8.3f} {med[0][1]:8.3f}")
    print(f"{'with -p no:flockai':26s} {med[1][0]:8.3f} {med[1][1]:8.3f}")
    print(f"{'difference':26s} {med[0][0] - med[1][0]:8.3f} {med[0][1] - med[1][1]:8.3f}")
    print(f"heavy libraries imported by a run that flies nothing: {heavy}")


if __name__ == "__main__":
    main()
