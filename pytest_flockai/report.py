"""Moved to ``pytest_flockai.reports.files``; the old path warns once per name
(``_deprecation.py``) and will be removed."""

from ._deprecation import moved

__getattr__ = moved(__name__, {
    "BASELINE_SCHEMA": "pytest_flockai.reports.files.BASELINE_SCHEMA",
    "ReportError": "pytest_flockai.reports.files.ReportError",
    "SCHEMA": "pytest_flockai.reports.files.SCHEMA",
    "baseline_from_tests": "pytest_flockai.reports.files.baseline_from_tests",
    "build_report": "pytest_flockai.reports.files.build_report",
    "check_entries": "pytest_flockai.reports.files.check_entries",
    "check_writable": "pytest_flockai.reports.files.check_writable",
    "environment": "pytest_flockai.reports.files.environment",
    "format_kpi": "pytest_flockai.reports.files.format_kpi",
    "jsonable": "pytest_flockai.reports.files.jsonable",
    "load_baseline": "pytest_flockai.reports.files.load_baseline",
    "read_json": "pytest_flockai.reports.files.read_json",
    "regressions": "pytest_flockai.reports.files.regressions",
    "safe_name": "pytest_flockai.reports.files.safe_name",
    "table": "pytest_flockai.reports.files.table",
    "write_artifacts": "pytest_flockai.reports.files.write_artifacts",
    "write_json_atomic": "pytest_flockai.reports.files.write_json_atomic",
})
