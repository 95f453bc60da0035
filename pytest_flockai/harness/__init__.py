"""The pytest side of pytest-flockai, one concern per module; ``plugin.py`` holds
only the hooks and delegates here.

- ``options``: command-line and ini options;
- ``markers``: the ``kpi`` and ``flockai`` markers, parsed at collection into
  frozen dataclasses;
- ``recorder``: the flights of one test (in ``item.stash``) and their names;
- ``verdicts``: budgets and baseline regressions of one test -> its failure message;
- ``session``: reports collected on the controller, JSON and baseline files;
- ``terminal``: the KPI table at the end of the run;
- ``fixtures``: ``drone world pilot tasks probes mission flight``.
"""
