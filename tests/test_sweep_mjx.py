"""Issue 18: the batched sweep backend (MJX physics, the core's components in JAX)
against the per-flight core, on CPU.

Tolerance: 1 % on flight time, simulated time, energy and endurance (the issue
asks for 2 %). The batched path computes in float64 like the core (``jax.enable_x64``
around the backend), so where nothing touches the ground the two agree to
round-off (measured: 1e-15 relative without wind). What differs is physics MJX
does its own way: the contact solver (MJX's JAX Newton solver against MuJoCo's C
solver) at take-off from the pad and at touchdown, where a landing detected one
physics step later moves the flight time by 2-4 ms of 3.5 s (1e-3), and the
fluid ellipsoid's added mass (a thousandth of the drag ellipsoid's, see
airframe/model.py), which the batched drag leaves out. The flight book counts
phases in 20 ms ticks, so one tick of 3.5 s is 0.6 %: 1 % keeps a tick of margin.
"""

import math

import mujoco
import numpy as np
import pytest

import pytest_flockai as fa
from pytest_flockai.airframe.model import build_spec

REL = 0.01
KPIS = ("sim_time_s", "flight_time_s", "energy_total_j", "energy_motors_j", "endurance_s",
        "battery_remaining", "distance_m")
NEEDS_JAX = "the mjx backend needs JAX and MJX: pip install 'pytest-flockai[mjx]'"


def _jax():
    pytest.importorskip("jax", reason=NEEDS_JAX)
    pytest.importorskip("mujoco.mjx", reason=NEEDS_JAX)


def _hover():
    return fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=1.0))


def _zigzag():
    """The datasheet Mavic: its motors are the DC motor model (energy/rotors.py)."""
    pilot = fa.pilots.ZigZag(area=((0.0, 0.0), (20.0, 10.0)), altitude=10.0, spacing=10.0,
                             speed=6.0)
    return fa.Mission(fa.drone("dji-mavic-2-pro-datasheet"), pilot, seed=3)


def _agree(cpu, bat):
    assert list(bat.columns) == list(cpu.columns)
    assert list(bat["end_reason"]) == list(cpu["end_reason"])
    assert bat["error"].isna().all()
    for k in KPIS:
        rel = (bat[k] / cpu[k] - 1.0).abs()
        assert (rel <= REL).all(), f"{k}: cpu {list(cpu[k])} mjx {list(bat[k])}"


def test_hover_over_payload_and_wind_agrees_with_the_core_and_repeats():
    """One test, so the batch compiles once (a module fixture would compile again on
    each xdist worker): payload x wind, the same sweep again, and a battery-reserve
    mission of the same batch structure (4 variants, payload differing)."""
    _jax()
    axes = dict(payload_kg=[0.0, 0.008], wind_mps=[0.0, 2.0])
    cpu = fa.sweep(_hover(), workers=1, **axes)
    bat = fa.sweep(_hover(), backend="mjx", device="cpu", **axes)
    assert list(cpu["end_reason"]) == ["landed"] * 4
    _agree(cpu, bat)
    # the variants really differ (a test that cannot fail would not see a lost axis)
    assert bat["energy_total_j"][2] > 1.4 * bat["energy_total_j"][0]
    # determinism: same seed, same DataFrame
    again = fa.sweep(_hover(), backend="mjx", device="cpu", **axes)
    cols = [c for c in bat.columns if c != "error"]
    assert bat[cols].equals(again[cols])
    # the battery's reserve sends the drone home to land (EndConditions -> go_home)
    reserve = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0),
                         until="battery_reserve")
    axes = dict(payload_kg=[0.0, 0.008], battery__reserve_fraction=[0.95, 0.97])
    cpu = fa.sweep(reserve, workers=1, **axes)
    bat = fa.sweep(reserve, backend="mjx", device="cpu", **axes)
    assert list(cpu["end_reason"]) == ["landed"] * 4
    assert cpu["flight_time_s"][1] < 0.8 * cpu["flight_time_s"][0]     # 3 % of the charge, not 5
    _agree(cpu, bat)


def test_zigzag_with_turbulent_wind_and_a_motor_model_agrees_with_the_core():
    _jax()
    axes = dict(payload_kg=[0.0, 0.2], wind_mps=[4.0])
    cpu = fa.sweep(_zigzag(), workers=1, **axes)
    bat = fa.sweep(_zigzag(), backend="mjx", **axes)
    assert list(cpu["end_reason"]) == ["landed", "landed"]
    _agree(cpu, bat)
    assert (bat["distance_m"] > 40.0).all()          # it flew the legs (20 + 10 + 20 m)


def test_the_batched_drag_is_mujocos_fluid_ellipsoid():
    """MJX has only the inertia-box fluid model; the batched step applies the
    ellipsoid's blunt drag itself: the same force as MuJoCo's C fluid model."""
    _jax()
    import jax
    from pytest_flockai.sweeps.batched import energy, params
    m = fa.Mission(fa.drone("dji-mavic-2-pro"), fa.pilots.Hover())
    _, num, _ = params.variant(m)
    model = build_spec(m.drone, None, physics_dt=0.002).compile()
    data = mujoco.MjData(model)
    rng = np.random.default_rng(1)
    with jax.enable_x64(True):
        for _ in range(5):
            quat = rng.normal(size=4)
            quat /= np.linalg.norm(quat)
            vel, wind = rng.normal(0, 6, 3), rng.normal(0, 4, 3)
            data.qpos[3:7], data.qvel[:3], data.qvel[3:] = quat, vel, 0.0
            model.opt.wind[:] = wind
            mujoco.mj_forward(model, data)
            ours = np.asarray(energy.drag({k: jax.numpy.asarray(v) for k, v in num.items()
                                           if k in ("aero_size", "aero_c", "rho")},
                                          quat, vel, wind))
            assert np.allclose(ours, data.qfrc_fluid[:3], rtol=1e-6, atol=1e-9), (ours, data.qfrc_fluid[:3])
            assert np.linalg.norm(ours) > 0.1


def test_the_batched_rotor_drag_is_the_cores_h_force():
    """The batched step applies every rotor's H-force (airframe/rotor_drag.py) itself:
    the same world-frame force and torque as ``RotorDrag.step`` on the same state, and
    the batched profile power leaves out the H-force's work as ``Motors`` does."""
    _jax()
    import jax
    from types import SimpleNamespace

    from pytest_flockai.airframe.rotor_drag import RotorDrag
    from pytest_flockai.energy import Motors
    from pytest_flockai.energy.factory import flight_energy_model
    from pytest_flockai.energy.model import Meter
    from pytest_flockai.sweeps.batched import energy, params
    for name in ("dji-mavic-2-pro", "generic-hexa-680"):
        drone = fa.drone(name)
        m = fa.Mission(drone, fa.pilots.Hover())
        _, num, _ = params.variant(m)
        assert num["h_c"] > 0 and num["m_hk"] > 0
        rng = np.random.default_rng(2)
        n = drone.airframe.rotor_count
        with jax.enable_x64(True):
            p = {k: jax.numpy.asarray(v) for k, v in num.items()
                 if isinstance(v, (bool, float, np.ndarray))}
            for _ in range(4):
                quat = rng.normal(size=4)
                quat /= np.linalg.norm(quat)
                q = np.r_[0.0, 0.0, 10.0, quat]
                v = np.r_[rng.normal(0, 6, 3), rng.normal(0, 1.5, 3)]
                wind, act = rng.normal(0, 4, 3), rng.uniform(0.0, 8.0, n)
                act[0] = 0.0                                   # a stopped rotor: no force
                xfrc = np.zeros(6)
                core = RotorDrag(drone, SimpleNamespace(q=q, v=v, w=wind), act, xfrc, num["rho"])
                core.step(0.0)
                f, tq = energy.rotor_drag(p, quat, v, wind, act)
                assert np.allclose(np.asarray(f), xfrc[:3], rtol=1e-9, atol=1e-12)
                assert np.allclose(np.asarray(tq), xfrc[3:], rtol=1e-9, atol=1e-12)
                assert np.linalg.norm(xfrc[:3]) > 1e-3
            thrust = np.full(n, drone.mass_kg * 9.81 / n)
            vrel = np.array([12.0, 0.0, 0.0])
            usage = SimpleNamespace(v_rel_body=tuple(vrel), thrust=thrust.tolist())
            meter = Meter(flight_energy_model(drone.energy), drone, rho=num["rho"])
            motors = [c for _, c in meter.model.leaves() if isinstance(c, Motors)][0]
            want = sum(motors.power_parts(usage))
            got, _ = energy.motors(p, jax.numpy.asarray(thrust), jax.numpy.asarray(vrel),
                                   jax.numpy.asarray(num["m_vi0"]))
            assert float(got) == pytest.approx(want, rel=1e-9)


@pytest.mark.parametrize("make, words", [
    (lambda: fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Orbit(radius=2.0, altitude=1.0)),
     ["pilot = Orbit", "backend='process'"]),
    (lambda: fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0), fly_on="estimate"),
     ["fly_on = 'estimate'"]),
    (lambda: fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0),
                        components=[fa.Clocked()]), ["components = "]),
    (lambda: fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0),
                        world=fa.World.urban(seed=1)), ["world = "]),
])
def test_what_the_batched_path_does_not_fly_is_a_config_error_naming_it(make, words):
    with pytest.raises(fa.ConfigError) as exc:
        fa.sweep(make(), backend="mjx", payload_kg=[0.0])
    for w in words:
        assert w in str(exc.value)


@pytest.mark.parametrize("axes, words", [
    (dict(payload_kg=0.1), ["payload_kg = 0.1", "list"]),
    (dict(wind_mps=[[1.0, 2.0]]), ["wind_mps", "shape (1, 2)"]),
    (dict(wind_mps=["calm"]), ["wind_mps = 'calm'"]),
])
def test_a_bad_axis_is_a_config_error_with_the_batched_backend_too(axes, words):
    with pytest.raises(fa.ConfigError) as exc:
        fa.sweep(_hover(), backend="mjx", **axes)
    for w in words:
        assert w in str(exc.value)
