"""CI runs the README's test command as written: no extra flags that change
what the tests see (``-p no:cacheprovider`` turned the flight cache off in CI only)."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_ci_runs_the_readme_test_command_as_written():
    readme = (ROOT / "README.md").read_text()
    quick = readme[readme.index("## Quick start"):]
    block = quick[quick.index("```bash"):quick.index("```", quick.index("```bash") + 7)]
    (command,) = [line.split(".venv/bin/pytest ", 1)[1].strip() for line in block.splitlines()
                  if ".venv/bin/pytest tests" in line]
    assert command == "tests -n 2"
    ci = (ROOT / ".ci" / "run").read_text()
    runs = re.findall(r'-m pytest (.*)', ci)
    assert len(runs) == 2
    for args in runs:
        words = args.split()
        assert " ".join(words[:3]) == command, args
        assert set(words[3:]) <= {"-rs"}, args       # reporting only: -rs lists the skips
