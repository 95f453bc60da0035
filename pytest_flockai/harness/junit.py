"""KPIs in pytest's JUnit XML (``--junitxml``), valid against the schema of its family.

pytest's default family, ``xunit2``, follows ``junit-10.xsd``, which allows no
``<properties>`` inside a ``<testcase>`` (neither does the legacy ``xunit1``
format by that schema). So every KPI is written once as a property of the
test suite, named ``flockai[<nodeid>].<kpi>`` (``flockai[<nodeid>].<flight>.<kpi>``
when the test flew several flights); the testcases stay as pytest writes
them. The JSON report (``--flockai-json``) has the same KPIs with their
flights, budgets and regressions.
"""

from __future__ import annotations

import math

# private: the LogXML of --junitxml, as pytest's fixtures use it
from _pytest.junitxml import xml_key

NOTE = ("pytest-flockai: KPIs are in --junitxml as suite properties flockai[<nodeid>].<kpi> "
        "(the JUnit schema allows no properties on a testcase)")


def properties(entries) -> list[tuple[str, str]]:
    out = []
    for e in entries:
        flights = e.get("flights") or []
        prefix_flight = len(flights) > 1
        for f in flights:
            for k, v in (f.get("kpis") or {}).items():
                name = f"{f['name']}.{k}" if prefix_flight else k
                out.append((f"flockai[{e['nodeid']}].{name}", value_text(v)))
    return out


def add_to_suite(config, entries) -> bool:
    """Add the KPIs of ``entries`` as suite properties; False without --junitxml."""
    xml = config.stash.get(xml_key, None)
    if xml is None:
        return False
    for name, value in properties(entries):
        xml.add_global_property(name, value)
    return True


def value_text(v) -> str:
    try:
        v = float(v)
    except (TypeError, ValueError):
        return "nan" if v is None else str(v)
    return repr(v) if math.isfinite(v) else str(v)
