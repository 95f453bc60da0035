"""The plugin and the package load the heavy libraries on first use: a pytest run
that flies nothing, and ``import pytest_flockai``, import none of MuJoCo, pandas,
NumPy, ONNX Runtime or OpenCV; every public name still resolves. Fresh processes
(this one has them loaded). The time it saves: ``benchmarks/plugin_overhead.py``."""

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
HEAVY = ("mujoco", "pandas", "numpy", "onnxruntime", "cv2")


def python(code: str, cwd) -> str:
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    out = subprocess.run([sys.executable, "-c", code], cwd=cwd, env=env, capture_output=True,
                         text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    return out.stdout


def loaded(names=HEAVY) -> str:
    return f"print('LOADED', sorted(m for m in {names!r} if m in sys.modules))"


def test_a_pytest_run_that_flies_nothing_imports_no_heavy_library(tmp_path):
    (tmp_path / "test_one.py").write_text(
        "import pytest\n\ndef test_one():\n    assert 1 + 1 == 2\n\n"
        "@pytest.mark.kpi(flight_time_s='>= 1 s')\ndef test_budget_without_a_flight():\n"
        "    pass\n")
    out = python("import sys, pytest\n"
                 "rc = pytest.main(['-q', '-p', 'no:cacheprovider', 'test_one.py'])\n"
                 "print('PLUGIN', 'pytest_flockai.plugin' in sys.modules, 'RC', int(rc))\n"
                 + loaded(), tmp_path)
    assert "PLUGIN True RC 1" in out, out         # the budget was parsed and checked
    assert "1 failed, 1 passed" in out and "flew no mission" in out, out
    assert "LOADED []" in out, out


def test_importing_the_package_is_light_and_every_public_name_resolves(tmp_path):
    out = python("import sys\nimport pytest_flockai as fa\n" + loaded() + "\n"
                 "names = [n for n in fa.__all__ if getattr(fa, n) is None]\n"
                 "print('NONE', names)\n"
                 "print('MISSION', fa.Mission.__module__, fa.pilots.Hover.__name__)\n"
                 "print('SUBPACKAGE', fa.world.World is fa.World, fa.energy.__name__)\n"
                 "print('DIR', {'Mission', 'drone', 'World'} <= set(dir(fa)))\n"
                 "try:\n    fa.no_such_name\nexcept AttributeError as e:\n    print('ERR', e)\n",
                 tmp_path)
    first = out.splitlines()[0]
    assert first == "LOADED []", out
    assert "NONE []" in out and "MISSION pytest_flockai.mission.mission Hover" in out
    assert "SUBPACKAGE True pytest_flockai.energy" in out and "DIR True" in out
    assert "has no attribute 'no_such_name'" in out
