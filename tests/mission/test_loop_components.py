"""The flight loop's components, each on its own (synthetic inputs, no flight),
plus the per-flight state rules: a user component, a battery sensor flown twice."""

import math

import numpy as np
import pytest

import pytest_flockai as fa
from pytest_flockai.comm.traffic import Traffic
from pytest_flockai.control.stages import DONE, LANDING, PILOT, RETURN, TAKEOFF, StageMachine
from pytest_flockai.energy.integrator import EnergyIntegrator
from pytest_flockai.mission.book import FlightBook
from pytest_flockai.mission.state import EventLog, VehicleState
from pytest_flockai.phases import PHASES


class _Data:                       # the two MjData fields the components read
    def __init__(self, n_rot=4, ncon=0):
        self.act = np.zeros(n_rot)
        self.ncon = ncon


class _Meter:                      # a constant-power meter: P = 100 W + 1 W per busy fraction
    def __init__(self):
        self.seen = []

    def step(self, u):
        self.seen.append((u.dt, u.soc_busy, u.tx_bytes))
        return 100.0 + u.soc_busy


def _state(**kw):
    s = VehicleState(e_usable=kw.pop("e_usable", 1e6))
    s.q, s.v = [0.0, 0.0, 10.0, 1.0, 0.0, 0.0, 0.0], [0.0] * 6
    for k, v in kw.items():
        setattr(s, k, v)
    return s


def test_energy_integrator_on_a_synthetic_trace_charges_every_interval_once():
    s, tr, meter = _state(), Traffic(), _Meter()
    integ = EnergyIntegrator(s, meter, _Data(), tr, None, energy_hz=20.0, n_rotors=4)
    dt, t = 0.02, 0.0
    for _ in range(101):             # 2.00 s of 50 Hz ticks
        tr.add(10, 1, 0, 0)          # 10 bytes every tick
        if t >= integ.next_due:
            integ.step(t)
        t = round(t + dt, 10)
    integ.finish(2.05)
    assert s.energy_j == pytest.approx(100.0 * 2.05, rel=1e-12)      # nothing lost, nothing twice
    assert sum(d for d, _, _ in meter.seen) == pytest.approx(2.05)
    assert tr.bytes_out == 101 * 10 and tr.packets_out == 101
    assert s.battery_remaining == pytest.approx(1.0 - 200.0 / 1e6)   # as of the last full interval


def test_flight_book_on_a_velocity_trace():
    s, ev = _state(stage=PILOT), EventLog()
    book = FlightBook(s, ev, 0.02)
    t = 0.0
    for i in range(100):             # 1 s hovering, then 1 s at 5 m/s east
        v = 0.0 if i < 50 else 5.0
        s.v = [v, 0.0, 0.0, 0.0, 0.0, 0.0]
        s.speed = v
        s.sp = [0.0] * 10
        s.q = [0.3, 0.4, 0.0, 1, 0, 0, 0]       # 0.5 m from the setpoint
        book.step(t)
        t += 0.02
    times = dict(zip(PHASES, book.phase_time))
    assert times["hover"] == pytest.approx(1.0)
    assert times["move"] + times["accelerating"] == pytest.approx(1.0)
    assert times["accelerating"] > 0                     # the step in speed is an acceleration
    assert book.distance_m == pytest.approx(5.0 * 50 * 0.02)
    assert book.max_speed_mps == 5.0
    assert book.tracking_error_max_m == pytest.approx(0.5)
    assert [e["phase"] for e in ev.items][:2] == ["hover", "accelerating"]


def test_stage_machine_takes_off_flies_returns_and_lands():
    s, ev = _state(), EventLog()
    s.home = (0.0, 0.0, 0.0)
    data = _Data()
    pilot = fa.pilots.Waypoints([(5.0, 0.0, 2.0)], speed=5.0)
    sm = StageMachine(s, pilot, ev, data, accel=2.0, climb_speed=2.0, descent_speed=1.0,
                      return_home=True)
    seen, t = [], 0.0
    while s.stage != DONE and t < 60:
        s.qc = s.q = [s.sp[0], s.sp[1], s.sp[2], 1, 0, 0, 0]     # a perfect follower
        s.vc = s.v = [s.sp[3], s.sp[4], s.sp[5], 0, 0, 0]
        if s.stage == LANDING and s.sp[2] <= 0.0:
            data.ncon = 1                                         # touching the ground
        sm.step(t)
        if not seen or seen[-1] != s.stage:
            seen.append(s.stage)
        t += 0.02
    assert seen == [TAKEOFF, PILOT, RETURN, LANDING, DONE]
    assert s.end_reason == "landed" and s.t_land is not None
    assert [e["stage"] for e in ev.items] == ["takeoff", "pilot", "return", "landing", "landed"]


class Geofence(fa.Clocked):
    """The README's example of a user component: end the flight outside a radius."""

    period_s = 0.1

    def __init__(self, radius_m):
        self.radius_m = radius_m

    def bind(self, run):
        super().bind(run)
        self.run = run

    def step(self, t):
        self.advance_clock()
        q = self.run.vehicle.q
        if math.hypot(q[0], q[1]) > self.radius_m:
            self.run.event(t, "geofence", x=q[0], y=q[1])
            self.run.stop("geofence")


def test_a_user_component_runs_on_its_clock_and_can_end_the_flight():
    pilot = fa.pilots.Waypoints([(40.0, 0.0, 10.0)], speed=5.0)
    r = fa.Mission(fa.drone("dji-mavic-2-pro"), pilot, components=[Geofence(15.0)]).run()
    assert r.end_reason == "geofence"
    ev = [e for e in r.events if e["kind"] == "geofence"]
    assert len(ev) == 1 and 15.0 < ev[0]["x"] < 16.0
    assert r.scenario["components"] == [{"type": "Geofence", "period_s": 0.1}]
    with pytest.raises(fa.ConfigError, match=r"components\[0\] = 3 is not a Clocked"):
        fa.Mission(fa.drone("dji-mavic-2-pro"), pilot, components=[3])


def test_battery_sensor_reads_each_flights_own_battery():
    """Regression: flown twice, the second flight's battery sensor read a
    constant, the first flight's final charge (the mission had set a lambda
    on the user's sensor only when it had none)."""
    sensor = fa.sensors.BatterySensor(rate_hz=1.0)
    m = fa.Mission(fa.drone("dji-mavic-2-pro"), fa.pilots.Hover(10, 20), sensors=[sensor])
    first = m.run().telemetry["sensor.battery"].dropna()
    second = m.run().telemetry["sensor.battery"].dropna()
    assert second.nunique() > 5                      # it falls during the flight
    assert second.iloc[0] == pytest.approx(first.iloc[0])
    np.testing.assert_allclose(second.to_numpy(), first.to_numpy())
    assert sensor.source is None                     # nothing was assigned onto the user's object


def test_configuration_errors_are_raised_when_the_mission_is_built():
    d = fa.drone("dji-mavic-2-pro")
    d.sim.physics_hz = 20.0                           # below its control rate
    with pytest.raises(fa.ConfigError, match="physics_hz = 20 must be >= control_hz"):
        fa.Mission(d, fa.pilots.Hover(10, 5))


def test_the_users_pilot_is_not_mutated_by_a_flight():
    pilot = fa.pilots.Hover(10, 5)
    before = dict(vars(pilot))
    fa.Mission(fa.drone("dji-mavic-2-pro"), pilot).run()
    assert vars(pilot) == before


def test_a_users_camera_sees_each_flights_own_world():
    """A camera added to the drone without a world of its own takes the world of
    each flight; it used to keep the first flight's world for every later one."""
    cam = fa.sensors.Camera(name="eye")
    d = fa.drone("dji-mavic-2-pro")
    d.add_sensor(cam)
    seen = []

    def model(frame):
        seen.append(len(cam.last_truth.objects))
        return 0.0
    task = fa.Task(fa.ml.PythonModel(model, macs=1), sensor="eye", period_s=1.0)
    crowd = fa.World.scene(people=[(x, y) for x in range(-4, 5, 2) for y in range(-4, 5, 2)])
    fa.Mission(d, fa.pilots.Waypoints([(0, 0, 15)], speed=2), world=crowd, tasks=[task]).run()
    assert max(seen) == 25
    seen.clear()
    fa.Mission(d, fa.pilots.Waypoints([(0, 0, 15)], speed=2), world=fa.World.scene(),
               tasks=[task]).run()
    assert seen and max(seen) == 0
    assert cam.world is None
