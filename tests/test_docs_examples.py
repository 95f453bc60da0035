"""Every Python code block of every page under docs/ runs, top to bottom in one
namespace per page, as a reader would paste them; a page's blocks may define
tests (functions named test_*), which are called too.

A block fenced as ```python is executed; a block that is not meant to run (an
output listing, a shell command) uses another fence (```text, ```bash)."""

import os
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PAGES = sorted((ROOT / "docs").rglob("*.md"))


def _blocks(page: Path) -> list[str]:
    return re.findall(r"^```python\n(.*?)^```", page.read_text(), re.S | re.M)


@pytest.mark.parametrize("page", [p for p in PAGES if _blocks(p)],
                         ids=lambda p: str(p.relative_to(ROOT)))
def test_every_docs_example_runs(page, tmp_path):
    cwd = os.getcwd()
    os.chdir(ROOT)                       # examples use paths relative to the repository
    ns: dict = {"__name__": f"docs:{page.name}", "TMP": tmp_path}
    try:
        for i, block in enumerate(_blocks(page)):
            try:
                exec(compile(block, f"{page.relative_to(ROOT)} python block {i}", "exec"), ns)
            except Exception as exc:
                pytest.fail(f"{page.name} python block {i} fails: {type(exc).__name__}: {exc}\n{block}")
        for name, fn in list(ns.items()):
            if name.startswith("test_") and callable(fn) and not getattr(fn, "__wrapped__", None) \
                    and not hasattr(fn, "pytestmark"):
                fn()                      # plain test functions; marked ones need the plugin
    finally:
        os.chdir(cwd)

