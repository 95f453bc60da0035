"""The documentation cannot drift. Every Python block of fixtures/models/README.md runs
(README.md's in tests/project/test_readme.py, docs/' in tests/project/test_docs_examples.py), and every
repository file the README, the docs pages and the benchmark results name exists."""

import re
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCS = ["README.md", "fixtures/models/README.md", "benchmarks/RESULTS.md",
        *sorted(str(p.relative_to(ROOT)) for p in (ROOT / "docs").rglob("*.md"))]
PATH_RE = re.compile(r"`((?:pytest_flockai|tests|example_tests|benchmarks|fixtures|docs|\.ci)"
                     r"/[A-Za-z0-9_./-]*[A-Za-z0-9_])`")


def blocks(doc):
    return re.findall(r"```python\n(.*?)```", (ROOT / doc).read_text(), re.S)


@pytest.mark.parametrize("i, block", list(enumerate(blocks("fixtures/models/README.md"))))
def test_fixtures_models_readme_blocks_run(i, block, monkeypatch):
    monkeypatch.chdir(ROOT)              # the block uses paths relative to the repository
    monkeypatch.setattr("sys.path", list(__import__("sys").path))
    ns = {"__name__": "fixtures_models_readme"}
    exec(compile(block, f"fixtures/models/README.md python block {i}", "exec"), ns)
    assert ns["task"].device.name == "raspberry-pi-4" and ns["cheap"].name == "blobs"


@pytest.mark.parametrize("doc", DOCS)
def test_every_repository_path_the_docs_name_exists(doc):
    named = set(PATH_RE.findall((ROOT / doc).read_text()))
    missing = sorted(p for p in named if "*" not in p and "<" not in p
                     and not (ROOT / p).exists() and not (ROOT / p.split("::")[0]).exists())
    assert missing == [], f"{doc} names files that are not in the repository: {missing}"


def test_mujoco_log_is_ignored_not_tracked():
    assert "MUJOCO_LOG.TXT" in (ROOT / ".gitignore").read_text().split()
    if not (ROOT / ".git").exists() or shutil.which("git") is None:
        pytest.skip("not a git checkout")
    tracked = subprocess.run(["git", "ls-files", "MUJOCO_LOG.TXT"], cwd=ROOT,
                             capture_output=True, text=True).stdout
    assert tracked == ""
