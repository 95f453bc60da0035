"""The batched backend's free body derived from the blueprint without compiling a MuJoCo
model per variant (``rigid_model.free_body``) against the body read from the compiled
model (``rigid_model.model_of``), and the sweep's fallback to the compile where the two
differ (``engine._checked``)."""

import numpy as np
import pytest

import pytest_flockai as fa
from pytest_flockai.sweeps import axes
from pytest_flockai.sweeps.batched import params as P
from pytest_flockai.sweeps.batched import rigid_model as RM

NEEDS_JAX = "the batched backend needs JAX and MJX: pip install 'pytest-flockai[mjx]'"
BLUEPRINTS = ("crazyflie-2-1", "dji-mavic-2-pro", "generic-hexa-680")
#: a payload sweep, axes that change the blueprint's airframe, and rotor parameters
AXES = {
    "payload_kg": [0.0, 0.0013, 0.0047],
    "mass_kg": [1.05, 0.93],                       # x the blueprint's mass
    "arm_length_m": [1.1, 0.9],
    "body_size_m": [1.2, 0.85],
    "inertia_kg_m2": [1.3, 0.8],
    "drag_area_m2": [1.5, 0.7],
    "time_constant_s": [2.0, 0.5],
    "max_speed_rad_s": [1.1, 0.95],
    "torque_coeff": [1.2, 0.8],
    "diameter_m": [1.05, 0.97],
}


def _value(drone, name, factor):
    """An axis value: the blueprint's own scaled by ``factor`` (payload: as given)."""
    if name == "payload_kg":
        return factor * drone.mass_kg / 0.03
    section, field = ("airframe", name) if name in type(drone.airframe).FIELDS else ("rotor", name)
    own = getattr(getattr(drone, section), field)
    return [factor * x for x in own] if isinstance(own, (list, tuple)) else factor * own


def _leaves_equal(a, b, rtol=1e-12):
    import jax
    la, lb = jax.tree_util.tree_leaves(a), jax.tree_util.tree_leaves(b)
    assert len(la) == len(lb)
    for x, y in zip(la, lb):
        x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
        assert x.shape == y.shape
        assert np.all((x == y) | (np.abs(x - y) <= rtol * np.abs(y))), (x, y)


def _variants(blueprint):
    base = fa.Mission(fa.drone(blueprint), fa.pilots.Hover(altitude=1.0, duration=1.0))
    for name, factors in AXES.items():
        for f in factors:
            yield name, axes.apply(base, {name: _value(base.drone, name, f)})


@pytest.mark.parametrize("blueprint", BLUEPRINTS)
def test_the_derived_free_body_equals_the_compiled_models(blueprint):
    pytest.importorskip("jax", reason=NEEDS_JAX)
    n = 0
    for name, m in _variants(blueprint):
        key, num, body = P.variant(m, physics="jax")
        ckey, cnum, cbody = P.variant(m, physics="jax", derive=False)
        assert key[-1] == ("free", m.drone.airframe.rotor_count), name
        assert key[:-1] == ckey[:-1] and ckey[-1][3] == key[-1][1], name
        assert RM.same_body(body, cbody), (name, body, cbody)
        _leaves_equal(body, cbody)
        _leaves_equal(num, cnum)
        n += 1
    assert n == sum(len(v) for v in AXES.values())


def test_numbers_the_compile_refuses_are_left_to_the_compile():
    d = fa.drone("crazyflie-2-1")
    assert RM.free_body(d, 0.002, 1.225) is not None
    d.airframe.inertia_kg_m2 = (1e-5, 1e-5, 3e-5)          # breaks A + B >= C
    assert RM.free_body(d, 0.002, 1.225) is None


@pytest.mark.jax
def test_a_derivation_that_differs_from_the_compile_compiles_every_member():
    pytest.importorskip("jax", reason=NEEDS_JAX)
    from pytest_flockai.sweeps.batched import setup
    base = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=1.0))
    members, groups = [], {}
    for i, p in enumerate([0.0, 0.001, 0.002, 0.003]):
        m = axes.apply(base, {"payload_kg": p})
        key, num, body = P.variant(m, physics="jax")
        members.append((i, m, num, body))
    groups[key] = members
    setup._COMPILED.clear()                                 # nothing compiled before
    good, compiled = setup.checked(dict(groups))
    assert compiled == 4 and list(good) == [key] and good[key] == members
    again, compiled = setup.checked(dict(groups))           # the same blueprints: reused
    assert compiled == 0 and again == good
    wrong = members[:2] + [(2, members[2][1], members[2][2],
                            members[2][3]._replace(c_blunt=members[2][3].c_blunt * (1 + 1e-9)))] \
        + members[3:]
    fixed, compiled = setup.checked({key: wrong})
    assert compiled == 4                    # the checks reuse the compiles above; all four
    (ckey, got), = fixed.items()
    assert ckey[-1][0] != "free" and [g[0] for g in got] == [0, 1, 2, 3]
    for (_, m, _, body), (_, _, _, mine) in zip(got, members):
        assert RM.same_body(body, P.compiled_body(m)) and RM.same_body(body, mine)
