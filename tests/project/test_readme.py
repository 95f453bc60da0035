"""Every Python example in the README runs, top to bottom in one namespace, as a
reader would paste them; the plain test it defines is called too. The README stays an
entry point: at most 15 KB, and every page it links to exists."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
TEXT = (ROOT / "README.md").read_text()
BLOCKS = re.findall(r"```python\n(.*?)```", TEXT, re.S)


@pytest.mark.slow
def test_every_readme_example_runs(monkeypatch):
    monkeypatch.chdir(ROOT)
    ns: dict = {"__name__": "readme"}
    for i, block in enumerate(BLOCKS):
        try:
            exec(compile(block, f"README.md python block {i}", "exec"), ns)
        except Exception as exc:
            pytest.fail(f"README python block {i} fails: {type(exc).__name__}: {exc}\n{block}")
    ns["test_what_if_bigger_battery"]()                       # "A test in 20 lines"
    assert 27 * 60 < ns["r"].kpis["flight_time_s"] < 30 * 60  # "about 28.4 min"


def test_the_readme_is_an_entry_point():
    assert len(TEXT.encode()) <= 15 * 1024
    quick = TEXT.split("## Quick start", 1)[1].split("##", 1)[0]
    commands = re.findall(r"```bash\n(.*?)```", quick, re.S)[0].strip().splitlines()
    assert len(commands) == 2 and "example_tests" in commands[0] and "tests" in commands[1]


def test_every_link_of_the_readme_and_docs_exists():
    pages = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
    missing = []
    for page in pages:
        for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", page.read_text()):
            if "://" in target:
                continue
            if not (page.parent / target).exists():
                missing.append(f"{page.relative_to(ROOT)} -> {target}")
    assert missing == []


@pytest.mark.slow
def test_the_readme_test_file_passes_under_pytest(pytester):
    """'A test in 20 lines', saved as a test file: both tests pass with the plugin, the
    marked one included (its budgets are checked against the survey flight)."""
    pytester.makepyfile(test_readme_example=BLOCKS[0])
    res = pytester.runpytest_subprocess("-p", "no:cacheprovider", "-q")
    res.assert_outcomes(passed=2)
