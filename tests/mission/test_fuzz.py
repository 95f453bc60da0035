"""Property-based fuzz: valid-by-the-docs scenarios across
blueprints, payloads, batteries, pilots, winds up to 25 m/s, ``until`` values
and seeds; every flight (also the partial result of a SimulationError) must
keep the invariants, and nothing but the documented ``SimulationError`` may
escape.

Derandomized. CI runs ``FLOCKAI_FUZZ_EXAMPLES`` scenarios (default 12); the
long mode is ``FLOCKAI_FUZZ_EXAMPLES=300 pytest tests/mission/test_fuzz.py``.
"""

import math
import os

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import pytest_flockai as fa
from pytest_flockai import strategies as fst
from pytest_flockai.errors import SimulationError

pytestmark = pytest.mark.slow

EXAMPLES = int(os.environ.get("FLOCKAI_FUZZ_EXAMPLES", "12"))
DRONES = ("crazyflie-2-1", "dji-mavic-2-pro", "generic-hexa-680")
SCALE = {"crazyflie-2-1": 0.2, "dji-mavic-2-pro": 1.0, "generic-hexa-680": 1.0}  # metres per unit
PARTS = ("energy_motors_j", "energy_proc_j", "energy_comm_j")
SHARES = ("energy_share_motors", "energy_share_proc", "energy_share_comm")


@st.composite
def scenarios(draw):
    name = draw(st.sampled_from(DRONES))
    cap = fa.drone(name).battery.capacity_mah
    k = SCALE[name]
    pilot = draw(st.one_of(
        st.builds(fa.pilots.Hover, st.floats(1.0, 20.0).map(lambda a: a * k), st.floats(0.0, 5.0)),
        st.builds(lambda x, y, z, v: fa.pilots.Waypoints([(x * k, y * k, z * k)], speed=v),
                  st.floats(-15, 15), st.floats(-15, 15), st.floats(1.0, 15.0), st.floats(0.5, 8.0)),
        st.builds(lambda w, h, a, s, v: fa.pilots.ZigZag(((0, 0), (w * k, h * k)), a * k, s * k, v),
                  st.floats(5, 30), st.floats(5, 30), st.floats(2, 15), st.floats(3, 15),
                  st.floats(1.0, 8.0)),
        st.builds(lambda r, a, v, laps: fa.pilots.Orbit((0, 0), r * k, a * k, v, laps=laps),
                  st.floats(2, 15), st.floats(2, 15), st.floats(0.5, 6.0), st.floats(0.05, 0.5))))
    until = draw(st.one_of(st.floats(0.2, 20.0), st.just("landed"), st.just("battery_reserve")))
    return dict(
        drone=fa.drone(name, battery_mah=draw(fst.batteries(0.3 * cap, 1.5 * cap)),
                       payload_kg=draw(fst.payloads(name))),
        pilot=pilot, wind=draw(st.one_of(st.none(), fst.winds(max_speed=25.0))),
        until=until, seed=draw(fst.seeds()))


def check_invariants(r):
    k = r.kpis
    bad = [n for n, v in k.items() if not isinstance(v, float) or math.isnan(v)]
    assert not bad, f"NaN or non-float KPIs: {bad}"
    total = k["energy_total_j"]
    assert total >= 0 and all(k[p] >= 0 for p in PARTS)
    assert total == pytest.approx(sum(k[p] for p in PARTS), rel=1e-9, abs=1e-9)
    if total > 0:
        assert sum(k[s] for s in SHARES) == pytest.approx(1.0, abs=1e-9)
    assert 0.0 <= k["battery_remaining"] <= 1.0
    assert k["crashed"] in (0.0, 1.0)
    times = [n for n in k if n.endswith("_s")]
    assert times and all(k[n] >= 0 for n in times), {n: k[n] for n in times if k[n] < 0}
    tel = r.telemetry
    assert tel["battery_remaining"].between(0.0, 1.0).all()
    assert (tel.index >= 0).all() and r.sim_time_s >= 0


COUNT = {"flights": 0, "simulation_errors": 0}


@settings(max_examples=EXAMPLES, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(sc=scenarios())
def test_every_fuzzed_flight_keeps_the_invariants(sc):
    m = fa.Mission(sc["drone"], sc["pilot"], wind=sc["wind"], until=sc["until"], seed=sc["seed"],
                   max_time_s=60.0, max_wall_s=60.0)
    try:
        r = m.run()
    except SimulationError as exc:        # documented: diverged or reset physics, wall time
        COUNT["simulation_errors"] += 1
        r = exc.result
    COUNT["flights"] += 1
    check_invariants(r)


def test_report_the_fuzz_count(capsys):
    """Prints how many scenarios the fuzz flew (run after it: same module)."""
    with capsys.disabled():
        print(f"\nfuzz: {COUNT['flights']} scenarios flown, {COUNT['simulation_errors']} ended in "
              f"a SimulationError (partial results checked too)")
