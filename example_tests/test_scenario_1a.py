"""Scenario 1-A of the paper: the Mavic 2 Pro surveys an area with no ML task.

The paper reports 30 min 06 s of flight, motors ~91 % and communication ~3 %
of the energy. Our figures come from the simulated flight: see the README's
"Paper vs pytest-flockai" table for the comparison and the reasons they differ.
"""

import pytest

import pytest_flockai as fa


@pytest.mark.flockai(drone="dji-mavic-2-pro", seed=0)
@pytest.mark.kpi(endurance_s=">= 28 min", energy_share_motors=">= 85%",
                 energy_share_comm="< 3%", crashed="== 0", tracking_error_max_m="<= 1 m")
def test_survey_without_ml(flight):
    # the pattern is flown and the drone is back home
    last = flight.telemetry.iloc[-1]
    assert abs(last.x) < 1.0 and abs(last.y) < 1.0 and flight.end_reason == "landed"


@pytest.mark.flockai(drone="dji-mavic-2-pro", seed=0)
@pytest.mark.kpi(endurance_s=">= 33 min", flight="4500mAh")
def test_bigger_battery_flies_longer(flight, drone, pilot):
    # the paper's Listing 2: the same drone with a 4500 mAh battery
    big = fa.drone("dji-mavic-2-pro", battery_mah=4500)
    result = fa.Mission(big, pilot, seed=0, name="4500mAh").run()
    assert result.kpis["endurance_s"] > 1.1 * flight.kpis["endurance_s"]


@pytest.mark.parametrize("payload_kg, budget", [(0.0, ">= 28 min"), (0.2, ">= 21 min"), (0.4, ">= 16 min")])
def test_payload_costs_flight_time(payload_kg, budget, pilot, request):
    request.node.add_marker(pytest.mark.kpi(endurance_s=budget))
    d = fa.drone("dji-mavic-2-pro", payload_kg=payload_kg)
    r = fa.Mission(d, pilot, seed=0).run()
    assert r.kpis["crashed"] == 0


@pytest.mark.kpi(crashed="== 0", flight="headwind")
def test_headwind_costs_energy(pilot):
    still = fa.Mission(fa.drone("dji-mavic-2-pro"), pilot, seed=0, name="still").run()
    windy = fa.Mission(fa.drone("dji-mavic-2-pro"), pilot, seed=0, name="headwind",
                       wind=fa.Wind((-6.0, 0.0, 0.0))).run()
    assert windy.kpis["energy_total_j"] > still.kpis["energy_total_j"]
