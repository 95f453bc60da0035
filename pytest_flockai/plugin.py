"""pytest plugin entry point (pytest11: flockai). Thin for now: registers markers."""


def pytest_configure(config):
    config.addinivalue_line("markers", "kpi(**budgets): KPI budgets for the flights of this test")
    config.addinivalue_line("markers", "flockai(**settings): quick settings for the flockai fixtures")
