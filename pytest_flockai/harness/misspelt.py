"""A misspelt pytest-flockai mark is a collection error.

``@pytest.mark.flockia(...)`` or ``@pytest.mark.kpis(...)`` would otherwise be an
unknown mark that pytest only warns about: the test flies the default drone and no
budget is checked, so the gate is silently off. A mark that is not registered (by
pytest, a plugin or the user's ini ``markers``) and whose name is close to one of the
plugin's marks fails the collection of its module, naming the mark, the test and the
mark that was meant. ``--strict-markers`` (pytest's own) refuses every unregistered
mark; the docs recommend it.
"""

from __future__ import annotations

import difflib

import pytest

#: the marks this plugin registers (plugin.py, harness/flightcache.py)
OWN_MARKS = ("flockai", "kpi", "flockai_sweep", "flockai_cache")
#: how alike a name must be to count as a misspelling (difflib ratio): "kpis" and
#: "flockia" are 0.86, an unrelated "api" 0.67
CUTOFF = 0.8


def registered(config) -> set[str]:
    """The names of every registered mark (ini ``markers`` lines, ``name(args): text``)."""
    names = set()
    for line in config.getini("markers"):
        names.add(line.split(":", 1)[0].split("(", 1)[0].strip())
    return names


def meant(name: str, known: set[str]) -> str | None:
    """The plugin's mark ``name`` is a misspelling of, or None."""
    if name in known or name in OWN_MARKS:
        return None
    hits = difflib.get_close_matches(name.lower(), OWN_MARKS, n=1, cutoff=CUTOFF)
    return hits[0] if hits else None


def problems(items, known: set[str]) -> list[str]:
    """One line per misspelt mark on the collected ``items`` (each mark once)."""
    out: dict[tuple[str, str], str] = {}
    for item in items:
        if not isinstance(item, pytest.Item):
            continue
        for mark in item.iter_markers():
            target = meant(mark.name, known)
            if target is not None:
                out.setdefault((mark.name, item.name.split("[", 1)[0]), (
                    f"{item.name.split('[', 1)[0]}: @pytest.mark.{mark.name} is not a registered "
                    f"mark; did you mean @pytest.mark.{target}? (pytest-flockai refuses a mark "
                    f"this close to its own: unchecked, it would switch the test's budgets or "
                    f"settings off; run with --strict-markers to refuse every unknown mark)"))
    return list(out.values())


class MisspeltMarks:
    """Turns a collector's report into a collection error when one of its items
    carries a misspelt pytest-flockai mark."""

    def __init__(self, config) -> None:
        self.config = config
        self._known: set[str] | None = None

    @pytest.hookimpl(wrapper=True)
    def pytest_make_collect_report(self, collector):
        report = yield
        if report.passed and report.result:
            if self._known is None:
                self._known = registered(self.config)
            lines = problems(report.result, self._known)
            if lines:
                report.outcome = "failed"
                report.longrepr = "\n".join(lines)
                report.result = []
        return report
