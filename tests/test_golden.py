"""The golden scenarios (tests/golden/scenarios.py) fly as they were recorded:
the same KPIs, end reasons, event counts, telemetry rows and energy breakdown.
A reshaping of the loop that moves any figure fails here, with the difference."""

import json
import math

import pytest

from golden import scenarios as golden

RECORDED = json.loads(golden.GOLDEN.read_text())


def _diff(path, want, got, out):
    if isinstance(want, dict):
        for k in sorted(set(want) | set(got if isinstance(got, dict) else {})):
            if not isinstance(got, dict) or k not in got:
                out.append(f"{path}{k}: missing now (was {want.get(k)!r})")
            elif k not in want:
                out.append(f"{path}{k}: new ({got[k]!r})")
            else:
                _diff(f"{path}{k}.", want[k], got[k], out)
    elif isinstance(want, float) or isinstance(got, float):
        w, g = float(want), float(got)
        if not (w == g or (math.isnan(w) and math.isnan(g))
                or math.isclose(w, g, rel_tol=1e-9, abs_tol=1e-12)):
            out.append(f"{path[:-1]}: recorded {w!r}, now {g!r}")
    elif want != got:
        out.append(f"{path[:-1]}: recorded {want!r}, now {got!r}")


@pytest.mark.parametrize("name", sorted(RECORDED))
def test_golden_scenario_unchanged(name):
    got = json.loads(json.dumps(golden.fly(name), default=float))
    out: list = []
    _diff("", RECORDED[name], got, out)
    assert not out, f"golden scenario {name!r} moved:\n" + "\n".join(out[:40])
