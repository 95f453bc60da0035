"""Every JAX twin of the batched backend against the core function it twins, one at a
time, on random states and on the edge cases (saturated mixer, empty battery,
vortex-ring descent, a stopped rotor, a zero-length leg).

The battery's voltage, resistance and current, the wind's intensities and OU
coefficients and the legs' timing are one formula called with ``xp`` (``math`` in
the core, ``jax.numpy`` in the batch): their tests check the wiring around the
formula (state, cut-off hold, height threshold). The controller, mixer, motors,
legs and paths, drag and H-force are twins: their tests are what keeps them from
drifting. Tolerances: 1e-9 relative (float64 on both sides; the twins reorder a few
sums). Run with the ``[mjx]`` extra; CI's newest stage fails if these skip.
"""

import math
from types import SimpleNamespace

import numpy as np
import pytest

import pytest_flockai as fa
from pytest_flockai.airframe.rotor_drag import RotorDrag
from pytest_flockai.control.controller import CascadedController
from pytest_flockai.control.trajectory import Leg, waypoint_path
from pytest_flockai.energy import Motors
from pytest_flockai.energy.battery import Circuit
from pytest_flockai.energy.factory import flight_energy_model
from pytest_flockai.energy.tree import Meter
from pytest_flockai.mission.plan import resolve
from pytest_flockai.world.wind import Wind

pytestmark = pytest.mark.jax
jax = pytest.importorskip("jax", reason="the batched twins need JAX: pip install 'pytest-flockai[mjx]'")
jnp = jax.numpy
pytest.importorskip("mujoco.mjx", reason="pip install 'pytest-flockai[mjx]'")
from pytest_flockai.sweeps.batched import control as C  # noqa: E402
from pytest_flockai.sweeps.batched import energy as E  # noqa: E402
from pytest_flockai.sweeps.batched import params as P  # noqa: E402

REL = 1e-9


@pytest.fixture(autouse=True)
def _x64():
    with jax.enable_x64(True):
        yield


def _tree(p):
    return jax.tree_util.tree_map(jnp.asarray, p)


def _close(got, want, rel=REL, atol=1e-12):
    got, want = np.asarray(got, dtype=float), np.asarray(want, dtype=float)
    assert np.allclose(got, want, rtol=rel, atol=atol), (got, want)


def _unit(rng):
    q = rng.normal(size=4)
    return q / np.linalg.norm(q)


@pytest.mark.parametrize("name", ["crazyflie-2-1", "dji-mavic-2-pro", "generic-hexa-680"])
def test_controller_twin_matches_cascaded_controller(name):
    """Random states, near and far from the setpoint: the far ones saturate the tilt, the
    vertical acceleration and (large yaw and attitude errors) the mixer."""
    drone = fa.drone(name)
    core = CascadedController(drone, 0.01)
    c = _tree(core.batch_params())
    rng = np.random.default_rng(7)
    saturated = 0
    for k in range(24):
        scale = 0.2 if k % 3 == 0 else 6.0
        q = np.r_[rng.normal(0, scale, 3), _unit(rng) if k % 2 else [1.0, 0, 0, 0]]
        v = np.r_[rng.normal(0, scale, 3), rng.normal(0, scale, 3)]
        sp = np.r_[rng.normal(0, 2, 3), rng.normal(0, 2, 3), rng.normal(0, 1, 3), rng.uniform(-3, 3)]
        integ = rng.normal(0, 0.5, 3)
        core.ix, core.iy, core.iz = integ
        f = core.update(list(q), list(v), list(sp))
        got, g_int = C.controller(c, jnp.asarray(integ), jnp.asarray(q), jnp.asarray(v),
                                  jnp.asarray(sp), 0.01)
        _close(got, f)
        _close(g_int, [core.ix, core.iy, core.iz])
        saturated += min(f) == 0.0 or max(f) == pytest.approx(core.fmax)
    assert saturated >= 3                  # the saturated mixer was exercised


def test_mixer_twin_matches_the_saturated_mixer():
    """Collective and torques from hover to far beyond what the rotors can give: every
    branch of ``_mix`` (fits; roll/pitch fit and the collective moves; roll/pitch scaled;
    yaw scaled)."""
    core = CascadedController(fa.drone("dji-mavic-2-pro"), 0.01)
    B, fmax = jnp.asarray(np.asarray(core.B)), core.fmax
    rng = np.random.default_rng(3)
    for k in range(40):
        T = rng.uniform(0.0, 4.5 * fmax)
        tx, ty, tz = rng.normal(0, [0.1, 0.1, 0.05][k % 3] * (1 + k // 4) * fmax, 3)
        want = core._mix(T, tx, ty, tz)
        _close(C.mix(B, fmax, T, tx, ty, tz), want)


def _motors(name):
    drone = fa.drone(name)
    meter = Meter(flight_energy_model(drone.energy), drone, rho=1.2)
    return drone, next(c for _, c in meter.model.leaves() if isinstance(c, Motors))


@pytest.mark.parametrize("name", ["dji-mavic-2-pro", "dji-mavic-2-pro-datasheet", "generic-hexa-680"])
def test_motor_power_twin_matches_motors(name):
    """Hover, forward flight (wake interference), climb, vortex-ring descent, autorotation
    (negative total) and a stopped rotor; the induced-velocity state carried over ticks."""
    drone, core = _motors(name)
    mp = _tree(core.batch_params())
    n = drone.airframe.rotor_count
    hover = drone.mass_kg * 9.81 / n
    rng = np.random.default_rng(11)
    cases = [(0.0, 0.0, 0.0), (12.0, 0.0, 0.5), (3.0, -4.0, 2.0), (0.0, 0.0, -3.0),
             (0.5, 0.2, -6.0), (1.0, 0.0, -12.0), (0.0, 0.0, -25.0)]
    cases += [tuple(rng.normal(0, 6, 3)) for _ in range(12)]
    vi = jnp.asarray(core.batch_params().vi0)
    for k, vrel in enumerate(cases):
        thrust = hover * rng.uniform(0.3, 1.8, n)
        if k % 4 == 1:
            thrust[k % n] = 0.0                      # a stopped rotor
        want = sum(core.power_parts(SimpleNamespace(v_rel_body=vrel, thrust=list(thrust))))
        got, vi = E.motors(mp, jnp.asarray(thrust), jnp.asarray(vrel), vi)
        assert float(got) == pytest.approx(want, rel=REL), vrel
        _close(vi, core._vi)


@pytest.mark.parametrize("chemistry", ["lipo", "li-ion"])
def test_battery_twin_matches_circuit_draw_down_to_empty(chemistry):
    """Draws from full to beyond empty: the resistance's rise, the cut-off hold, a load
    beyond the pack's maximum power (the discriminant below 0)."""
    core = Circuit(chemistry=chemistry, cells=3, capacity_ah=0.05, resistance_ohm=0.06,
                   cutoff_v_per_cell=3.0 if chemistry == "lipo" else 2.5)
    b = _tree(core.batch_params())
    s = {"b_soc": 1.0, "b_below": 0.0, "b_cut": False, "b_v": 0.0, "b_vmin": b.v0}
    rng = np.random.default_rng(5)
    cut_at = None
    for k in range(400):
        power = 0.0 if k % 50 == 7 else rng.uniform(5.0, 40.0)
        if k == 390:
            power = 1e4                                      # beyond the pack's maximum
        s = {**s, "b_soc": core.soc}               # each draw from the core's own state
        loss = core.draw(power, 0.5)
        got, s = E.battery(b, s, power, 0.5)
        assert float(got) == pytest.approx(loss, rel=REL, abs=1e-12)
        assert float(s["b_soc"]) == pytest.approx(core.soc, rel=REL, abs=1e-12)
        assert float(s["b_v"]) == pytest.approx(core.voltage_v, rel=REL)
        assert bool(s["b_cut"]) == core.cutoff
        cut_at = k if cut_at is None and core.cutoff else cut_at
    assert core.soc < 0.05 and cut_at is not None and cut_at < 390    # emptied, cut off


@pytest.mark.parametrize("wind", [Wind((6.0, 2.0, 0.0)), Wind((3.0, 0.0, 0.0), gust_std=1.5),
                                  Wind((0.0, 4.0, 0.0), gust_std=0.8, gust_tau_s=2.0)])
def test_wind_twin_matches_wind_sampler(wind):
    """A climb and a descent through the Dryden layer: intensities and time constants
    follow the height (recomputed past 0.5 m, as the core), the same noise, the same gusts."""
    dt = 0.01
    rng = np.random.default_rng(2)
    core = wind.sampler(np.random.default_rng(9), dt)
    w = _tree(wind.batch_params())
    s = {"w_g": jnp.asarray(core.g), "w_coef": jnp.zeros(4), "w_h": jnp.nan}
    heights = np.r_[np.linspace(0.0, 80.0, 150), np.linspace(80.0, 2.0, 150)] + rng.normal(0, 0.1, 300)
    for h in heights:
        want = core.step(h)
        buf, k = core._buf, core._k - 3
        got, st = E.wind_step(w, s, h, jnp.asarray(buf[k:k + 3]), dt)
        s = st
        _close(got, want)


def test_leg_and_path_twins_match_the_trajectory():
    """Triangular and trapezoidal legs, a zero-length leg, times before, inside and after."""
    rng = np.random.default_rng(4)
    sp = [0.0] * 10
    for k in range(10):
        p0 = rng.normal(0, 10, 3)
        p1 = p0 if k == 0 else p0 + rng.normal(0, [0.3, 5.0, 30.0][k % 3], 3)
        speed, accel = rng.uniform(1, 12), rng.uniform(0.5, 2.5)
        leg = Leg(p0, p1, speed, accel)
        for t in np.r_[-0.5, 0.0, rng.uniform(0, leg.duration + 1.0, 12), leg.duration]:
            leg.fill(t, sp)
            pos, vel, acc, dur = C.leg(jnp.asarray(p0), jnp.asarray(p1), speed, accel, t)
            _close(np.r_[pos, vel, acc], sp[:9], atol=1e-9)
            assert float(dur) == pytest.approx(leg.duration, rel=REL, abs=1e-12)
    start, pts = (0.0, 0.0, 1.0), rng.normal(0, 8, (5, 3))
    path = waypoint_path(start, [tuple(p) for p in pts], 5.0, 2.0)
    ends = jnp.asarray(pts)
    starts = jnp.concatenate([jnp.asarray([start]), ends[:-1]])
    for t in np.r_[np.sort(rng.uniform(0, path.duration + 2.0, 30)), path.duration]:
        done = path.fill(t, sp)
        pos, vel, acc, got_done = C.path(starts, ends, 5.0, 2.0, t)
        _close(np.r_[pos, vel, acc], sp[:9], atol=1e-9)
        assert bool(got_done) == done


def test_rotor_drag_twin_matches_the_cores_h_force():
    """Random attitudes, rates, winds and rotor thrusts (one rotor stopped)."""
    for name in ("dji-mavic-2-pro", "generic-hexa-680"):
        drone = fa.drone(name)
        _, num, _ = P.variant(fa.Mission(drone, fa.pilots.Hover()))
        a = _tree(num.aero)
        assert num.aero.h_c > 0
        rng = np.random.default_rng(2)
        for _ in range(6):
            quat = _unit(rng)
            q = np.r_[0.0, 0.0, 10.0, quat]
            v = np.r_[rng.normal(0, 6, 3), rng.normal(0, 1.5, 3)]
            wind, act = rng.normal(0, 4, 3), rng.uniform(0.0, 8.0, drone.airframe.rotor_count)
            act[0] = 0.0
            xfrc = np.zeros(6)
            RotorDrag(drone, SimpleNamespace(q=q, v=v, w=wind), act, xfrc, num.aero.rho).step(0.0)
            f, tq = E.rotor_drag(a, quat, v, wind, act)
            _close(f, xfrc[:3])
            _close(tq, xfrc[3:])
            assert np.linalg.norm(xfrc[:3]) > 1e-3


def test_body_drag_twin_is_mujocos_fluid_ellipsoid():
    """MJX has only the inertia-box fluid model; the batched step applies the ellipsoid's
    blunt drag itself: the same force as MuJoCo's C fluid model (1e-6: MuJoCo's own
    projected-area arithmetic)."""
    import mujoco

    from pytest_flockai.airframe.mjspec import build_spec
    m = fa.Mission(fa.drone("dji-mavic-2-pro"), fa.pilots.Hover())
    _, num, _ = P.variant(m)
    model = build_spec(m.drone, None, physics_dt=0.002).compile()
    data = mujoco.MjData(model)
    a = _tree(num.aero)
    rng = np.random.default_rng(1)
    for _ in range(6):
        quat = _unit(rng)
        vel, wind = rng.normal(0, 6, 3), rng.normal(0, 4, 3)
        data.qpos[3:7], data.qvel[:3], data.qvel[3:] = quat, vel, 0.0
        model.opt.wind[:] = wind
        mujoco.mj_forward(model, data)
        ours = E.drag(a, quat, vel, wind)
        _close(ours, data.qfrc_fluid[:3], rel=1e-6, atol=1e-9)
        assert np.linalg.norm(ours) > 0.1


def test_variant_params_are_the_core_objects_exports():
    """The batch's numbers are the core's declared exports (no private attributes), typed,
    and stack into one pytree."""
    m = fa.Mission(fa.drone("dji-mavic-2-pro-datasheet"), fa.pilots.Hover(altitude=3.0),
                   wind=fa.Wind((4.0, 0.0, 0.0)))
    _, num, _ = P.variant(m)
    ctrl = CascadedController(m.drone, resolve(m).ctrl_dt, rho=num.aero.rho).batch_params()
    assert num.ctrl.k_pos == ctrl.k_pos and num.ctrl.fmax == ctrl.fmax
    want = m.wind.batch_params()
    assert num.wind._replace(mean=None) == want._replace(mean=None)
    assert np.array_equal(num.wind.mean, want.mean) and num.wind.mean[0] == 4.0
    assert bool(num.motors.model) and num.battery.cells > 0
    stacked = jax.tree_util.tree_map(lambda *xs: jnp.stack([jnp.asarray(x) for x in xs]), num, num)
    assert stacked.ctrl.B.shape == (2,) + np.asarray(num.ctrl.B).shape
    assert math.isinf(num.pilot.duration)


def _free_model(name):
    from pytest_flockai.airframe.mjspec import build_spec
    spec = build_spec(fa.drone(name), None, physics_dt=0.002)
    spec.option.density = 0.0                   # the batch applies the drag itself
    return spec.compile()


@pytest.mark.parametrize("name", ["crazyflie-2-1", "dji-mavic-2-pro", "generic-hexa-680"])
def test_free_flight_step_is_mujocos_step_in_the_air(name):
    """``rigid.step`` against ``mj_step`` from the same random states in the air: rotor
    thrusts (the filter's state and a new command, some beyond the range), rates, an
    applied force and torque at the centre of mass."""
    import mujoco

    from pytest_flockai.sweeps.batched import rigid as R
    model = _free_model(name)
    data = mujoco.MjData(model)
    rm = _tree(R.model_of(model))
    rng = np.random.default_rng(8)
    hi = model.actuator_ctrlrange[:, 1]
    for _ in range(12):
        mujoco.mj_resetData(model, data)
        data.qpos[:3] = rng.normal(0, 3, 3) + [0, 0, 10.0]
        data.qpos[3:7] = _unit(rng)
        data.qvel[:] = np.r_[rng.normal(0, 4, 3), rng.normal(0, 3, 3)]
        data.act[:] = rng.uniform(0, hi)
        data.ctrl[:] = rng.uniform(-0.2 * hi, 1.2 * hi)
        data.xfrc_applied[1] = rng.normal(0, 0.3 * model.body_mass[1] * 9.81, 6)
        d = R.RigidData(0.0, data.qpos.copy(), data.qvel.copy(), data.act.copy(), False)
        got = R.step(rm, d, jnp.asarray(data.ctrl), jnp.asarray(data.xfrc_applied[1]))
        mujoco.mj_step(model, data)
        _close(got.qpos, data.qpos, rel=1e-9, atol=1e-12)
        _close(got.qvel, data.qvel, rel=1e-9, atol=1e-10)
        _close(got.act, data.act)
        assert not bool(got.contact)


def test_free_flight_ground_rests_and_lifts_off_like_mujoco():
    """On the pad: below the weight the body stays on the ground (MuJoCo's soft contact
    sinks it a fraction of a millimetre), above it both lift off within a step or two."""
    import mujoco

    from pytest_flockai.sweeps.batched import rigid as R
    model = _free_model("crazyflie-2-1")
    data = mujoco.MjData(model)
    rm = _tree(R.model_of(model))
    weight = model.body_mass[1] * 9.81
    for share, rises in ((0.8, False), (1.3, True)):
        mujoco.mj_resetData(model, data)
        d = R.RigidData(0.0, data.qpos.copy(), data.qvel.copy(), data.act.copy(), False)
        ctrl = np.full(model.nu, share * weight / model.nu)
        data.ctrl[:] = ctrl
        touched = []
        for _ in range(150):                               # 0.3 s
            mujoco.mj_step(model, data)
            d = R.step(rm, d, jnp.asarray(ctrl), jnp.zeros(6))
            touched.append(bool(d.contact))
        assert abs(float(d.qpos[2]) - data.qpos[2]) < (0.02 if rises else 1e-3), (share, d.qpos[2], data.qpos[2])
        assert (float(d.qpos[2]) > 0.02) == rises and (data.qpos[2] > 0.02) == rises
        assert touched[-1] == (not rises) and (rises or touched[20])   # fell the 1 mm onto the pad
        _close(d.qpos[3:7], [1.0, 0.0, 0.0, 0.0], atol=1e-9)


def _stage_twin(mission):
    """The core's StageMachine and the JAX twin's initial state, for a perfect tracker."""
    from pytest_flockai.control.stages import StageMachine
    from pytest_flockai.mission import parts
    from pytest_flockai.sweeps.batched import setup
    plan = resolve(mission)
    key, num, body = P.variant(mission, physics="jax")
    home = (0.0, 0.0, float(body.qpos0[2]))
    st = SimpleNamespace(home=home, stage=None, sp=[0.0] * 10, qc=list(home), vc=[0.0] * 3,
                         v=[0.0] * 6, t_land=None, end_reason=None)
    events = SimpleNamespace(add=lambda *a, **k: None)
    data = SimpleNamespace(ncon=0)
    accel = parts.trajectory_accel(plan, parts.controller(plan))
    core = StageMachine(st, plan.pilot, events, data, accel=accel, climb_speed=plan.climb_speed,
                        descent_speed=plan.descent_speed, return_home=plan.return_home)
    s0 = setup.init_states(setup.stack([num], to_jax=False),
                           setup.data([(0, mission, num, body)], None, "jax"), np.zeros((1, 3)),
                           len(body.rigid.tau))
    s = {k: jnp.asarray(v[0]) for k, v in s0.items() if k != "d"}
    return core, st, data, _tree(num), s, key[6], plan.ctrl_dt


@pytest.mark.parametrize("pilot, home_at", [
    (fa.pilots.Hover(altitude=2.0, duration=1.5), None),
    (fa.pilots.ZigZag(area=((0.0, 0.0), (12.0, 6.0)), altitude=5.0, spacing=6.0, speed=4.0), None),
    (fa.pilots.Waypoints([(3.0, 0.0, 3.0), (3.0, 4.0, 4.0)], speed=3.0, loop=True), 9.0),
])
def test_stage_machine_twin_matches_the_core_tick_by_tick(pilot, home_at):
    """Take-off, the pilot's plan (hover, legs, a looping path), return home (after the
    pilot, or sent by the battery reserve at ``home_at``) and landing, both driven by a
    vehicle that tracks the setpoint exactly and stops on the ground: the same stage and
    setpoint every tick, and the same landing tick."""
    mission = fa.Mission(fa.drone("dji-mavic-2-pro"), pilot)
    core, st, data, p, s, pkind, dt = _stage_twin(mission)
    step = jax.jit(lambda s1, t, q, v, c: C.stages(p, s1, t, q, v, c, pkind))
    home = jax.jit(lambda s1, t: C.go_home(p, s1, t, True))
    q, v = list(st.home), [0.0, 0.0, 0.0]
    stages_seen, landed_at, seen = set(), None, []
    for k in range(4000):
        t = k * dt
        if home_at is not None and abs(t - home_at) < 0.5 * dt:
            core.go_home(t)
            s = home(s, t)
        contact = q[2] <= st.home[2] + 1e-9
        data.ncon = int(contact)
        st.qc, st.vc, st.v = list(q), list(v), list(v) + [0.0] * 3
        core.step(t)
        seen.append((s, t, q + [1.0, 0.0, 0.0, 0.0], v + [0.0] * 3, contact))
        s, landed = step(s, t, jnp.asarray(q + [1.0, 0.0, 0.0, 0.0]),
                         jnp.asarray(v + [0.0] * 3), contact)
        assert int(s["stage"]) == st.stage, (t, int(s["stage"]), st.stage)
        _close(s["sp"], st.sp, atol=1e-9)
        stages_seen.add(st.stage)
        if st.stage == 4:                                   # DONE
            landed_at = t
            assert bool(landed) and float(s["t_land"]) == pytest.approx(st.t_land)
            break
        q, v = list(st.sp[:3]), list(st.sp[3:6])
        if q[2] <= st.home[2]:                             # the ground stops it
            q[2], v = st.home[2], [0.0, 0.0, 0.0]
    assert landed_at is not None and stages_seen >= {0, 1, 3, 4}
    assert (2 in stages_seen) == (pilot.__class__.__name__ != "Hover")   # returned home
    _batched_stages_agree(p, pkind, seen)


def _batched_stages_agree(p, pkind, seen):
    """The batch's stage machine (``engine._stages``: parts under batch-level conds) equals
    the twin on batches of ticks in mixed stages, stage changes included (stages exact,
    numbers to round-off)."""
    from pytest_flockai.sweeps.batched import engine
    from pytest_flockai.sweeps.batched.rigid import RigidData
    change = [k for k in range(1, len(seen)) if int(seen[k][0]["stage"]) != int(seen[k - 1][0]["stage"])]
    rng = np.random.default_rng(3)
    picks = sorted(set(change) | {k - 1 for k in change} | set(rng.integers(0, len(seen), 24)))
    for part in (picks, [k for k in picks if int(seen[k][0]["stage"]) == 1], picks[:1]):
        if not part:
            continue
        rows = [{**seen[k][0], "d": RigidData(jnp.asarray(seen[k][1]), jnp.asarray(seen[k][2]),
                                            jnp.asarray(seen[k][3]), jnp.zeros(4), jnp.asarray(seen[k][4]))}
                for k in part]
        sb = jax.tree_util.tree_map(lambda *x: jnp.stack(x), *rows)
        n = len(part)
        pb = jax.tree_util.tree_map(lambda x, n=n: jnp.stack([jnp.asarray(x)] * n), p)
        got, g_landed = jax.jit(lambda p1, s1: engine._stages(p1, s1, pkind))(pb, sb)
        want, w_landed = jax.jit(jax.vmap(lambda p1, s1: C.stages(
            p1, s1, s1["d"].time, s1["d"].qpos, s1["d"].qvel, s1["d"].contact, pkind)))(pb, sb)
        assert np.array_equal(np.asarray(g_landed), np.asarray(w_landed))
        for key in want:
            if key != "d":
                a, b = np.asarray(got[key]), np.asarray(want[key])
                if a.dtype.kind in "biu":
                    assert np.array_equal(a, b), key
                else:                   # XLA fuses the parts apart: last-bit differences
                    np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12, err_msg=key)


@pytest.mark.parametrize("ctrl_dt", [0.004, 0.02])
def test_flight_book_twin_matches_the_core(ctrl_dt):
    """Random velocities and stages, on the ground and in the air: phase ticks, distance,
    top speed, tracking error and the smoothed acceleration after every book step."""
    from pytest_flockai.mission.book import FlightBook, book_period
    period = book_period(ctrl_dt)
    st = SimpleNamespace(v=[0.0] * 6, airborne=True, speed=0.0, stage=0, q=[0.0] * 7,
                         sp=[0.0] * 10, phase=None)
    core = FlightBook(st, SimpleNamespace(add=lambda *a, **k: None), ctrl_dt)
    s = {"t_book": 0.0, "pv": jnp.zeros(3), "acc": 0.0, "stage": 0, "airborne": True,
         "ticks": jnp.zeros(6, dtype=jnp.int32), "dist": 0.0, "vmax": 0.0, "terr": 0.0,
         "sp": jnp.zeros(10), "b_next": 0.0}
    rng = np.random.default_rng(12)
    v = np.zeros(3)
    for k in range(1, 400):
        t = k * period
        if k % 150 == 0:
            v = np.zeros(3)
        elif k % 50 == 0:                                   # steps, then steady: accel, move
            v = v + rng.normal(0, 1.0, 3)
        st.v, st.speed = list(v) + [0.0] * 3, float(np.linalg.norm(v))
        st.stage = int(rng.choice([0, 1, 1, 1, 2, 3])) if k > 10 else 0
        st.airborne = k % 97 != 0
        st.q = list(rng.normal(0, 2, 3)) + [1.0, 0, 0, 0]
        st.sp = list(rng.normal(0, 2, 3)) + [0.0] * 7
        core.step(t)
        s = {**s, "stage": st.stage, "airborne": st.airborne, "sp": jnp.asarray(st.sp)}
        got = E.book(None, s, t, jnp.asarray(st.q), jnp.asarray(st.v), st.speed, period,
                     core.every_tick)
        s = {**s, **got}
        assert [int(n) for n in s["ticks"][:5]] == core.phase_ticks[:5], t
        assert float(s["dist"]) == pytest.approx(core.distance_m, rel=REL)
        assert float(s["vmax"]) == pytest.approx(core.max_speed_mps, rel=REL)
        assert float(s["terr"]) == pytest.approx(core.tracking_error_max_m, rel=REL)
        assert float(s["acc"]) == pytest.approx(core._acc, rel=REL, abs=1e-12)
    assert min(core.phase_ticks[:4]) > 0                     # every airborne phase was seen
