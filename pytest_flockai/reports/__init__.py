"""Reports people look at, and comparisons across commits.

- ``compare``: ``flockai compare BASE.json NEW.json``: per-test, per-KPI deltas,
  each KPI's better direction, exit status 1 on a regression beyond a threshold;
- ``history``: ``--flockai-history DIR`` keeps each run's KPIs with its git
  commit; ``flockai history DIR --kpi endurance_s`` prints (and draws) the trend;
- ``markdown``: the job summary (``--flockai-md PATH``, ``GITHUB_STEP_SUMMARY``);
- ``html``: the self-contained dashboard (``--flockai-html PATH``).

Everything here reads the plain data of the JSON report (``report.py``); none
of it needs pytest.
"""
