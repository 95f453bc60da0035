"""The shipped models are in the package (package data, in the wheel), the same bytes
as the recipes' files in fixtures/models/, and load by name."""

import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

import pytest_flockai as fa

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("name", sorted(fa.ml.SHIPPED))
def test_a_shipped_model_is_the_fixture_file_and_runs(name):
    path = fa.ml.shipped_path(name)
    assert path.read_bytes() == (ROOT / "fixtures" / "models" / path.name).read_bytes()
    model = fa.ml.shipped(name)
    assert model.name == name and model.macs > 0
    out = model(np.full((240, 320, 3), 90, np.uint8))
    assert np.all(np.isfinite(np.asarray(out if not isinstance(out, tuple) else out[0])))


def test_an_unknown_shipped_model_is_refused_with_the_names():
    with pytest.raises(fa.ConfigError, match=r"shipped model = 'yolo' is not allowed; allowed: "
                                             r"'detector'"):
        fa.ml.shipped("yolo")


@pytest.mark.slow
def test_the_wheel_carries_the_shipped_models(tmp_path):
    """Built as tests/project/test_packaging.py builds it (a venv with a setuptools that reads the
    SPDX licence); skipped when the package index cannot be reached."""
    subprocess.run([sys.executable, "-m", "venv", str(tmp_path / "v")], check=True)
    py = tmp_path / "v" / "bin" / "python"
    got = subprocess.run([py, "-m", "pip", "install", "-q", "setuptools>=77.0.1"],
                         capture_output=True, text=True)
    if got.returncode != 0:
        pytest.skip(f"setuptools cannot be installed here: {got.stderr[-300:]}")
    src = tmp_path / "src"
    shutil.copytree(ROOT, src, ignore=shutil.ignore_patterns(
        ".venv", ".git", "*.egg-info", "build", "__pycache__", ".pytest_cache", ".hypothesis",
        "docs", "benchmarks", "example_tests", "tests"))
    res = subprocess.run([py, "-m", "pip", "wheel", "-q", "--no-build-isolation", "--no-deps",
                          "-w", str(tmp_path / "dist"), str(src)], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr[-2000:]
    (whl,) = (tmp_path / "dist").glob("pytest_flockai-*.whl")
    names = set(zipfile.ZipFile(whl).namelist())
    for file, _ in fa.ml.SHIPPED.values():
        assert f"pytest_flockai/ml/shipped_models/{file}" in names
