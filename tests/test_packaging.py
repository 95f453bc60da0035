"""Issue 16: the build-system's setuptools lower bound is honest: the package
builds with exactly that version (``--no-build-isolation``), and the version
below it rejects the SPDX ``license = "MIT"`` string. Needs the package index
(as installing the package does); skipped when pip cannot reach it."""

import re
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parent.parent


def lower_bound() -> str:
    req = tomllib.loads((ROOT / "pyproject.toml").read_text())["build-system"]["requires"]
    (spec,) = [r for r in req if r.startswith("setuptools")]
    return re.fullmatch(r"setuptools>=([\d.]+)", spec.replace(" ", "")).group(1)


def test_the_bound_is_at_least_the_first_setuptools_with_spdx_licenses():
    assert tuple(int(x) for x in lower_bound().split(".")) >= (77, 0, 1)


@pytest.mark.parametrize("version, builds", [(None, True), ("76.1.0", False)])
def test_the_package_builds_with_the_oldest_allowed_setuptools(tmp_path, version, builds):
    version = version or lower_bound()
    subprocess.run([sys.executable, "-m", "venv", str(tmp_path / "v")], check=True)
    py = tmp_path / "v" / "bin" / "python"
    got = subprocess.run([py, "-m", "pip", "install", "-q", f"setuptools=={version}"],
                         capture_output=True, text=True)
    if got.returncode != 0:
        pytest.skip(f"setuptools=={version} cannot be installed here: {got.stderr[-300:]}")
    src = tmp_path / "src"
    shutil.copytree(ROOT, src, ignore=shutil.ignore_patterns(
        ".venv", ".git", "*.egg-info", "build", "__pycache__", ".pytest_cache", ".hypothesis",
        "docs", "benchmarks", "example_tests", "tests"))
    res = subprocess.run([py, "-m", "pip", "wheel", "-q", "--no-build-isolation", "--no-deps",
                          "-w", str(tmp_path / "dist"), str(src)], capture_output=True, text=True)
    if builds:
        assert res.returncode == 0, res.stderr[-2000:]
        assert list((tmp_path / "dist").glob("pytest_flockai-*.whl"))
    else:
        assert res.returncode != 0 and "project.license" in res.stdout + res.stderr
