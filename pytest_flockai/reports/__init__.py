"""Reports people look at, and comparisons across commits.

- ``compare``: ``flockai compare BASE.json NEW.json``: the scenario changes, then the
  regressions one row per KPI family and test, biggest first, grouped by cause, with a
  relative threshold and an absolute tolerance per KPI; exit status 1 on a regression;
- ``scenario``: what a flight was in a few words, and the difference between two runs;
- ``summary``: what the Markdown summary and the dashboard show (pytest's counts);
- ``history``: ``--flockai-history DIR`` keeps each run's KPIs with its git
  commit; ``flockai history DIR --kpi endurance_s`` prints (and draws) the trend;
- ``markdown``: the job summary (``--flockai-md PATH``, ``GITHUB_STEP_SUMMARY``);
- ``html``: the self-contained dashboard (``--flockai-html PATH``; ``html_assets``: its
  style and script).

Everything here reads the plain data of the JSON report (``report.py``); none
of it needs pytest.
"""

#: the public modules (``summary``, ``markdown`` and ``html`` are the plugin's own)
__all__ = ["compare", "history", "scenario"]
