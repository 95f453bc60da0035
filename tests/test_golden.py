"""The golden scenarios (tests/golden/scenarios.py) fly as they were recorded:
the same KPIs, end reasons, event counts, telemetry rows and energy breakdown.
A reshaping of the loop that moves any figure fails here, with the difference.

The figures were recorded on the newest dependency versions; other MuJoCo and
numpy releases round differently (1e-8 relative on the lowest allowed ones), so
``.ci/run``'s lowest-versions stage sets ``FLOCKAI_GOLDEN_REL_TOL=1e-6``."""

import json
import math
import os

import pytest

from golden import scenarios as golden

RECORDED = json.loads(golden.GOLDEN.read_text())
REL_TOL = float(os.environ.get("FLOCKAI_GOLDEN_REL_TOL", "1e-9"))


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
                or math.isclose(w, g, rel_tol=REL_TOL, abs_tol=1e-12)):
            out.append(f"{path[:-1]}: recorded {w!r}, now {g!r}")
    elif want != got:
        out.append(f"{path[:-1]}: recorded {want!r}, now {got!r}")


@pytest.mark.parametrize("name", sorted(RECORDED))
def test_golden_scenario_unchanged(name):
    got = json.loads(json.dumps(golden.fly(name), default=float))
    out: list = []
    _diff("", RECORDED[name], got, out)
    assert not out, f"golden scenario {name!r} moved:\n" + "\n".join(out[:40])
