"""Moved to ``pytest_flockai.reports.subcommands``; the old path warns once per name
(``_deprecation.py``) and will be removed."""

from .._deprecation import moved

__getattr__ = moved(__name__, {
    "add_parsers": "pytest_flockai.reports.subcommands.add_parsers",
    "close_matches": "pytest_flockai.reports.subcommands.close_matches",
    "run": "pytest_flockai.reports.subcommands.run",
})
