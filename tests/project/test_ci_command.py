"""CI runs the README's test command as written: the same extras installed, the same
pytest arguments, no extra flags that change what the tests see (``-p no:cacheprovider``
once turned the flight cache off in CI only; ``-rs`` now comes from pyproject.toml)."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_ci_runs_the_readme_test_command_as_written():
    readme = (ROOT / "README.md").read_text()
    quick = readme[readme.index("## Quick start"):]
    block = quick[quick.index("```bash"):quick.index("```", quick.index("```bash") + 7)]
    (line,) = [ln for ln in block.splitlines() if ".venv/bin/pytest tests" in ln]
    command = line.split(".venv/bin/pytest ", 1)[1].strip()
    assert command == "tests -n 2"
    (extras,) = re.findall(r'pip install -e "\.\[([^]]+)\]"', line)
    ci = (ROOT / ".ci" / "run").read_text()
    runs = re.findall(r'bin/pytest"? (.*)', ci)
    assert runs == [command, command]          # the newest versions, then the lowest
    assert "-m pytest" not in ci               # python -m pytest would add the cwd to sys.path
    # the newest stage installs what the README's command installs (then the linters)
    installs = re.findall(r'\$venv/bin/python" -m pip install --quiet -e "\.\[([^]]+)\]"', ci)
    assert installs[0] == extras, (installs, extras)
