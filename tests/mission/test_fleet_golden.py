"""The golden fleets (tests/golden/fleet_scenarios.py) fly as they were recorded
before the fleet loop was made faster: the same KPIs of every drone
and of the fleet, end reasons, event counts, telemetry rows and column sums and
energy breakdown. Same tolerance rule as tests/mission/test_golden.py."""

import json

import pytest
from golden import fleet_scenarios as golden
from test_golden import REL_TOL, diff

RECORDED = json.loads(golden.GOLDEN.read_text())


@pytest.mark.parametrize("name", sorted(RECORDED))
def test_golden_fleet_unchanged(name):
    got = json.loads(json.dumps(golden.fly(name), default=float))
    out = diff(name, RECORDED[name], got)
    assert not out, f"golden fleet {name!r} moved (rel tol {REL_TOL:g}):\n" + "\n".join(out[:40])
