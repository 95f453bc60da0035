"""Energy and battery must-shows. Endurance comes from simulated
flights until the battery is depleted, not from a formula on the side."""

import pytest

import pytest_flockai as fa
from pytest_flockai import ConfigError
from pytest_flockai.energy import Constant, Group, HoverPower

MIN = 60.0


def _hover_until_empty(bp, **kw):
    return fa.Mission(fa.drone(bp), fa.pilots.Hover(altitude=10.0), until="battery_depleted", **kw).run()


def _cruise_until_empty(bp="dji-mavic-2-pro", speed=25 / 3.6):
    return fa.Mission(fa.drone(bp), fa.pilots.Waypoints([(60000.0, 0.0, 10.0)], speed=speed),
                      until="battery_depleted").run()


@pytest.fixture(scope="module")
def mavic_hover():
    return _hover_until_empty("dji-mavic-2-pro")


@pytest.fixture(scope="module")
def mavic_cruise():
    return _cruise_until_empty()


@pytest.mark.slow
def test_mavic_hover_until_depleted_lasts_29_min(mavic_hover):
    r = mavic_hover
    assert r.end_reason == "battery_depleted"
    assert r.kpis["flight_time_s"] == pytest.approx(29 * MIN, rel=0.05)
    assert r.kpis["battery_remaining"] == pytest.approx(0.0, abs=1e-3)


@pytest.mark.slow
def test_mavic_25kmh_until_depleted_lasts_31_min_and_beats_hover(mavic_hover, mavic_cruise):
    r = mavic_cruise
    assert r.end_reason == "battery_depleted"
    # DJI: 31 min at 25 km/h. Nothing is fitted to it: the model gives 33.3 min (+7.4 %,
    # docs/explanation/validation.md), so the bound is the validation set's 12 %
    assert r.kpis["flight_time_s"] == pytest.approx(31 * MIN, rel=0.12)
    assert r.kpis["flight_time_s"] > mavic_hover.kpis["flight_time_s"]


@pytest.mark.slow
def test_crazyflie_hover_about_7_min():
    r = _hover_until_empty("crazyflie-2-1")
    assert r.kpis["flight_time_s"] == pytest.approx(7 * MIN, rel=0.15)


@pytest.fixture(scope="module")
def no_ml_flight():
    pilot = fa.pilots.ZigZag(area=((0, 0), (200, 100)), altitude=30, spacing=25, speed=8)
    return fa.Mission(fa.drone("dji-mavic-2-pro"), pilot, seed=0).run()


def test_no_ml_shares(no_ml_flight):
    k = no_ml_flight.kpis
    assert k["energy_share_motors"] == pytest.approx(0.90, abs=0.03)   # paper: ~91 %
    total = k["energy_share_motors"] + k["energy_share_proc"] + k["energy_share_comm"]
    assert total == pytest.approx(1.0, abs=1e-12)
    assert k["energy_total_j"] == pytest.approx(
        k["energy_motors_j"] + k["energy_proc_j"] + k["energy_comm_j"], rel=1e-12)
    assert k["mean_power_w"] * no_ml_flight.sim_time_s == pytest.approx(k["energy_total_j"], rel=1e-9)


def test_breakdown_has_sub_components(no_ml_flight):
    b = no_ml_flight.energy_breakdown
    for key in ("motors.induced", "motors.profile", "motors.climb_and_drag", "proc.fc",
                "proc.soc.idle", "proc.soc.active", "proc.io", "proc.sensors.camera", "comm.radio.idle",
                "comm.radio.tx"):
        assert key in b, key
    assert b["proc"] == pytest.approx(sum(v for k, v in b.items() if k.startswith("proc.")
                                          and k.count(".") == 1))
    tel = no_ml_flight.telemetry
    for c in ("energy_motors_j", "energy_proc_j", "energy_comm_j", "battery_remaining", "power_w"):
        assert c in tel
    assert tel.energy_motors_j.is_monotonic_increasing


def test_endurance_projects_flight_time(no_ml_flight):
    k = no_ml_flight.kpis
    e = fa.drone("dji-mavic-2-pro").battery.energy_j
    # at the mean drain: the load's mean power plus the battery's own I^2 R loss
    drain_w = k["mean_power_w"] + k["energy_battery_loss_j"] / no_ml_flight.sim_time_s
    assert k["endurance_s"] == pytest.approx(e / drain_w)
    assert 0.0 < k["energy_battery_loss_j"] < 0.05 * k["energy_total_j"]
    assert 25 * MIN < k["endurance_s"] < 33 * MIN


def _short(drone):
    return fa.Mission(drone, fa.pilots.Hover(altitude=5.0, duration=20.0), seed=0).run()


def test_listing4_customisation_changes_proc_energy_exactly():
    base = _short(fa.drone("dji-mavic-2-pro"))
    d = fa.drone("dji-mavic-2-pro")
    proc = d.energy.component("proc").copy()
    removed = sum(c.power_w for c in proc.component("sensors").children) + proc.component("io").power_w
    proc.remove(["sensors", "io"])
    fc = proc.component("fc")
    fc.set_description("DJI A3 flight controller")
    old_fc = fc.power_w
    fc.set_power(8.3)
    d.energy.replace("proc", proc)
    r = _short(d)
    t = r.sim_time_s
    assert t == base.sim_time_s        # the flight itself is unchanged
    expected = base.kpis["energy_proc_j"] + ((8.3 - old_fc) - removed) * t
    assert r.kpis["energy_proc_j"] == pytest.approx(expected, rel=1e-9)
    assert r.kpis["energy_motors_j"] == base.kpis["energy_motors_j"]


def test_user_component_and_hover_power_alternative():
    d = fa.drone("dji-mavic-2-pro")
    d.energy.component("proc").add(Constant("heater", 5.0, "de-icing"))
    r = _short(d)
    assert r.energy_breakdown["proc.heater"] == pytest.approx(5.0 * r.sim_time_s)
    d2 = fa.drone("dji-mavic-2-pro")
    d2.energy.replace("motors", HoverPower(power_w=95.02))      # the paper's released constant
    r2 = _short(d2)
    airborne = r2.kpis["flight_time_s"]
    assert r2.kpis["energy_motors_j"] == pytest.approx(95.02 * airborne, rel=0.01)


def test_headwind_costs_more_than_still_air():
    route = fa.pilots.Waypoints([(300.0, 0.0, 20.0)], speed=8.0)
    still = fa.Mission(fa.drone("dji-mavic-2-pro"), route, seed=0, return_home=False).run()
    route2 = fa.pilots.Waypoints([(300.0, 0.0, 20.0)], speed=8.0)
    head = fa.Mission(fa.drone("dji-mavic-2-pro"), route2, seed=0, return_home=False,
                      wind=fa.Wind((-6.0, 0.0, 0.0))).run()
    assert head.kpis["energy_motors_j"] > 1.05 * still.kpis["energy_motors_j"]


def test_battery_reserve_returns_home_and_lands():
    d = fa.drone("dji-mavic-2-pro", battery_mah=400)
    d.battery.internal_resistance_mohm = 7.8   # the Mavic's cells (3850 mAh), only fewer of them
    d.battery.reserve_fraction = 0.5      # ~90 s left: enough to fly back ~250 m and land from 20 m
    pilot = fa.pilots.Waypoints([(200.0, 0.0, 20.0), (200.0, 150.0, 20.0)], speed=6.0, loop=True)
    r = fa.Mission(d, pilot, until="battery_reserve").run()
    kinds = [e["kind"] for e in r.events]
    assert "battery_reserve" in kinds and r.end_reason == "landed"
    last = r.telemetry.iloc[-1]
    assert abs(last.x) < 1.0 and abs(last.y) < 1.0
    assert 0.0 < r.kpis["battery_remaining"] < d.battery.reserve_fraction


def test_bad_energy_input():
    d = fa.drone("dji-mavic-2-pro")
    with pytest.raises(ConfigError, match="power_w = -1"):
        d.energy.component("proc.fc").set_power(-1)
    with pytest.raises(ConfigError, match="power_w = nan"):
        Constant("x", float("nan"))
    with pytest.raises(ConfigError, match="no component 'gpu' to remove.*it has: fc, soc, io, sensors"):
        d.energy.component("proc").remove("gpu")
    with pytest.raises(ConfigError, match="motor_efficiency"):
        from pytest_flockai.energy import Motors
        Motors(figure_of_merit=0.6, motor_efficiency=1.2, esc_efficiency=0.9)
    with pytest.raises(ConfigError, match="esc_efficiency"):
        from pytest_flockai.energy import Motors
        Motors(figure_of_merit=0.6, motor_efficiency=0.8, esc_efficiency=0.0)
    with pytest.raises(ConfigError, match="reserve_fraction"):
        d.battery.reserve_fraction = -0.1
    with pytest.raises(ConfigError, match="capacity_mah = nan"):
        d.battery.capacity_mah = float("nan")
    with pytest.raises(ConfigError, match="already has a component 'fc'"):
        d.energy.component("proc").add(Constant("fc", 1.0))
    assert isinstance(d.energy.component("proc"), Group)


def test_paper_wifi_power_states_give_the_papers_comm_share():
    """With the paper's Wi-Fi figures (8.4 W tx/rx, 4.2 W idle) in the power-state
    form, communication takes ~3.5 % of the energy (paper: ~3 %); the default
    802.11 linear model (0.8 W idle, Feeney and Nilsson) gives well under 1 %."""
    from pytest_flockai.energy import RadioStates
    d = fa.drone("dji-mavic-2-pro")
    d.energy.component("comm").replace("radio", RadioStates("radio", tx_w=8.4, rx_w=8.4, idle_w=4.2))
    r = _short(d)
    base = _short(fa.drone("dji-mavic-2-pro"))
    assert 0.025 < r.kpis["energy_share_comm"] < 0.045
    assert base.kpis["energy_share_comm"] < 0.01
    b = r.energy_breakdown
    # one 256 B heartbeat up and a 64 B ack down per second at 6 Mbit/s
    t_tx = 256 * 8 / 6e6 * r.kpis["packets_out"]
    assert b["comm.radio.tx"] == pytest.approx(8.4 * t_tx, rel=1e-6)


def test_wake_immersion_is_geometry():
    """The aft rotor sits in the fore rotor's wake by how far that wake has sunk
    when it reaches it: h = L (V_ax + v_i) / V_par below the aft disc, immersion 1 - h / D."""
    from pytest_flockai.energy.rotors import wake_immersion
    L, D = 0.25, 0.221                          # Mavic 2 rotor spacing and propeller
    assert wake_immersion(L, 3.0, 0.5, D) == 0.0                # slow: the wake falls clear
    assert wake_immersion(L, 0.0, 10.0, D) == 1.0               # flat wake
    assert wake_immersion(L, 3.3, 6.94, D) == pytest.approx(1 - L * 3.3 / 6.94 / D)
    speeds = [2.0, 5.0, 8.0, 12.0, 20.0]
    values = [wake_immersion(L, 3.0, v, D) for v in speeds]
    assert values == sorted(values) and values[0] == 0.0 and values[-1] < 1.0
    np = pytest.importorskip("numpy")
    arr = wake_immersion(L, 3.0, np.array(speeds), D, maximum=np.maximum, minimum=np.minimum)
    assert list(arr) == pytest.approx(values)


@pytest.mark.slow
def test_cruise_beats_hover_on_a_small_folding_drone():
    """The Mini 3 Pro lasts longer at 21.6 km/h than in hover, as its maker says
    (34 against 30 min): translational lift outweighs the profile and parasite power and the
    aft rotors' wake ingestion at that speed."""
    hover = _hover_until_empty("dji-mini-3-pro").kpis["flight_time_s"]
    cruise = _cruise_until_empty("dji-mini-3-pro", speed=6.0).kpis["flight_time_s"]
    assert cruise / hover == pytest.approx(34 / 30, abs=0.05)
