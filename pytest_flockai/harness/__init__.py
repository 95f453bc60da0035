"""The pytest side of pytest-flockai, one concern per module; ``plugin.py`` holds
only the hooks and delegates here.

- ``options``: command-line and ini options;
- ``markers``: the ``kpi`` and ``flockai`` markers, parsed at collection into
  frozen dataclasses;
- ``recorder``: the flights of one test (in ``item.stash``) and their names;
- ``verdicts``: budgets and baseline regressions of one test -> its failure message;
- ``session``: reports collected on the controller, JSON and baseline files;
- ``terminal``: the KPI table at the end of the run;
- ``fixtures``: ``drone world pilot tasks probes mission flight``;
- ``sweeps``: the ``flockai_sweep`` mark and fixture;
- ``examples``: hypothesis examples counted, the shrunk one kept in full;
- ``flightcache``: the flight cache under pytest's cache directory;
- ``misspelt``: a mark name close to one of the plugin's is a collection error;
- ``ci_reports``: the Markdown summary and the HTML dashboard, written at the end;
- ``html_extras``: the KPI table and pictures as pytest-html extras;
- ``junit``: KPIs in pytest's JUnit XML, valid against its family's schema;
- ``signals``: SIGTERM ends the run the way Ctrl-C does, so the reports are written;
- ``rootdir``: path options in the space form do not move pytest's rootdir;
- ``tracebacks``: tracebacks pytest can format whatever instruction was interrupted.
"""
