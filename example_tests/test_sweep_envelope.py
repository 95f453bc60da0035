"""The Mavic 2 Pro's endurance envelope over payload x wind, with a budget.

Each variant is a short hover in a steady wind (30 s on station, about 50 s
flown with take-off and landing) and is gated on ``endurance_s``: the
projected flight time to depletion at that flight's mean drain. Flying every
variant until the battery is empty would take about 25 simulated minutes each;
the projection keeps the 3 x 3 grid under a minute on 2 cores.

    pytest example_tests/test_sweep_envelope.py --flockai-artifacts artifacts
writes the envelope as ``sweep.csv`` and ``sweep.png`` under
``artifacts/example_tests_test_sweep_envelope.py_test_mavic_endurance_envelope-185f6bfb42/``
(the test id as a folder name).
"""

import pytest

import pytest_flockai as fa

pytestmark = pytest.mark.flockai(drone="dji-mavic-2-pro",
                                 pilot=fa.pilots.Hover(altitude=10.0, duration=30.0))


@pytest.mark.flockai_sweep(payload_kg=[0.0, 0.25, 0.5], wind_mps=[0.0, 5.0, 10.0], workers=2)
# 0.5 kg: 15.3 min in still air to 17.3 min at 5 m/s (15.3 to 16.2 before issue 30's wake
# geometry: the aft rotors ingest less of the fore wake in a light wind); ">= 20 min" fails there
@pytest.mark.kpi(endurance_s=">= 15 min")
def test_mavic_endurance_envelope(flockai_sweep):
    df = flockai_sweep
    assert len(df) == 9 and df["error"].isna().all()
    calm = df[df["wind_mps"] == 0.0].sort_values("payload_kg")
    assert calm["endurance_s"].is_monotonic_decreasing   # every gram costs endurance
