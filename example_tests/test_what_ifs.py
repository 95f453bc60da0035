"""What-if questions beyond the paper: devices and execution modes, battery,
payload, wind (a hypothesis fuzz), a custom probe and a custom energy component."""

import math

import pytest
import scenarios
from hypothesis import given, settings

import pytest_flockai as fa
from pytest_flockai import cacheable, check_budgets
from pytest_flockai import strategies as fst

SHORT = dict(until=90.0)          # a 90 s slice of the survey is enough to project endurance


@pytest.mark.parametrize("execution", ["onboard", "remote"])
@pytest.mark.parametrize("device", ["raspberry-pi-4", "jetson-nano-5w", "jetson-nano-10w", "jetson-orin-nano"])
@pytest.mark.kpi(inference_latency_p50_s="<= 5 s", frames_dropped="== 0", crashed="== 0")
def test_device_by_execution_sweep(device, execution, models, city):
    # the drone carries `device` (a task naming another computer would add a second one)
    task = fa.Task(models["cnn"], period_s=5.0, execution=execution, name="cnn")
    r = fa.Mission(fa.drone("dji-mavic-2-pro", device=device), scenarios.survey(), world=city,
                   tasks=[task], seed=0, name=f"{device}-{execution}", **SHORT).run()
    assert r.scenario["computers"] == [{"name": device, "source": "blueprint"}]


@pytest.mark.kpi(endurance_s=">= 34 min", flight="4500mAh")      # 36.0 min (34.8 with the fitted Mavic)
def test_bigger_battery_flies_longer():
    """The paper's Listing 2: the same drone with a 4500 mAh battery."""
    base = fa.Mission(fa.drone("dji-mavic-2-pro"), scenarios.survey(), seed=0, name="3850mAh", **SHORT).run()
    big = fa.Mission(fa.drone("dji-mavic-2-pro", battery_mah=4500), scenarios.survey(), seed=0,
                     name="4500mAh", **SHORT).run()
    assert big.kpis["endurance_s"] == pytest.approx(base.kpis["endurance_s"] * 4500 / 3850, rel=0.01)


# measured (session 7): 30.7 / 23.1 / 18.0 min (29.7 / 22.7 / 18.0 with the Mavic's fitted efficiency)
@pytest.mark.parametrize("payload_kg, budget", [(0.0, ">= 29 min"), (0.2, ">= 22 min"), (0.4, ">= 17 min")])
def test_payload_costs_flight_time(payload_kg, budget, request):
    request.node.add_marker(pytest.mark.kpi(endurance_s=budget))
    d = fa.drone("dji-mavic-2-pro", payload_kg=payload_kg)
    assert fa.Mission(d, scenarios.survey(), seed=0, **SHORT).run().kpis["crashed"] == 0


@pytest.mark.flockai_cache("readwrite")   # derandomized: the same flights each run, so cache them
@settings(max_examples=12, deadline=None, database=None, derandomize=True)
@given(wind=fst.winds(max_speed=9.0), mah=fst.batteries(3400.0, 4500.0))
def test_fuzz_wind_and_battery_against_a_flight_time_budget(wind, mah):
    """Hypothesis looks for a wind and battery that break a 24-minute budget
    (derandomized: the same examples on every run, so CI is deterministic).
    The hardest case is still air with the smallest battery (25.3 min; 24.5 with the
    Mavic's motor efficiency fitted to DJI's hover time, before session 7): wind lowers hover power through translational lift. A failure would
    print the minimal wind and battery."""
    d = fa.drone("dji-mavic-2-pro", battery_mah=mah)
    r = fa.Mission(d, fa.pilots.Hover(altitude=20.0, duration=20.0), wind=wind, seed=0).run()
    fst.target_margin(r, endurance_s=">= 24 min")
    check_budgets(r, endurance_s=">= 24 min", crashed="== 0")


@cacheable     # collect() only reads the view: its flights may come from the flight cache
class Detections(fa.probes.Probe):
    """The paper's app-level probe: crowds detected per minute (section 4.5)."""
    name = "app"
    metrics = (fa.probes.Metric("detections_per_min", "1/min", "crowd detections per minute",
                                better="higher", kind="gauge"),)

    def collect(self, view):
        n = view.task_kpis.get("inference_count", 0.0)
        return {"detections_per_min": 60.0 * n / view.t if view.t > 0 else 0.0}


@pytest.mark.kpi({"app.detections_per_min": ">= 5"})
def test_custom_probe_is_budgetable(models, city):
    task = fa.Task(models["cheap"], period_s=5.0, name="cheap")
    r = fa.Mission(fa.drone("dji-mavic-2-pro"), scenarios.survey(), world=city, tasks=[task], seed=0,
                   probes=[Detections(period_s=10.0)], **SHORT).run()
    assert "app.detections_per_min" in r.telemetry


def test_custom_energy_component_listing4():
    """Listing 4: drop the sensors and I/O from E_proc, set the flight controller to 8.3 W."""
    base = fa.Mission(fa.drone("dji-mavic-2-pro"), scenarios.survey(), seed=0, **SHORT).run()
    d = fa.drone("dji-mavic-2-pro")
    proc = d.energy.component("proc")
    removed = sum(c.power_w for c in proc.component("sensors").children) + proc.component("io").power_w
    proc.remove("sensors", "io")
    proc.component("fc").set_description("DJI A3 flight controller").set_power(8.3)
    r = fa.Mission(d, scenarios.survey(), seed=0, **SHORT).run()
    t = r.sim_time_s
    assert r.kpis["energy_proc_j"] == pytest.approx(base.kpis["energy_proc_j"] + (0.3 - removed) * t)
    assert math.isclose(r.kpis["energy_motors_j"], base.kpis["energy_motors_j"])
