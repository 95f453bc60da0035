"""A sweep checks each axis value on the base mission once per process: a repeated sweep
of the same base does not apply its values again, a changed base does, and a refused
value is refused every time (``sweeps/axes.py``, ``check_values``)."""

import pytest

import pytest_flockai as fa
from pytest_flockai.sweeps import axes as _axes


def _hover(altitude=1.0):
    return fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=altitude, duration=1.0))


@pytest.fixture
def applied(monkeypatch):
    """The values ``check_value`` applied to a base (the real function, counted)."""
    seen = []
    real = _axes.check_value

    def counted(base, name, value):
        seen.append(value)
        real(base, name, value)
    monkeypatch.setattr(_axes, "check_value", counted)
    return seen


def test_a_repeated_sweep_of_the_same_base_applies_no_value_again(applied):
    values = [0.00131, 0.00137, 0.00137]
    _axes.check_values(_hover(), "payload_kg", values)
    assert applied == [0.00131, 0.00137]                   # each distinct value once
    _axes.check_values(_hover(), "payload_kg", values)     # an equal base: same pickle
    assert applied == [0.00131, 0.00137]
    _axes.check_values(_hover(altitude=2.0), "payload_kg", values)   # another base
    assert applied == [0.00131, 0.00137] * 2


def test_a_refused_value_is_refused_every_time(applied):
    for _ in range(2):
        with pytest.raises(fa.ConfigError, match="axis payload_kg = -0.1"):
            _axes.check_values(_hover(), "payload_kg", [-0.1])
    assert applied == [-0.1, -0.1]


def test_a_sweep_still_refuses_a_bad_value_after_a_good_sweep():
    m = _hover(altitude=1.5)
    fa.sweep(m, payload_kg=[0.00171], until=[0.05], workers=1)
    with pytest.raises(fa.ConfigError, match="axis payload_kg = -0.2"):
        fa.sweep(m, payload_kg=[0.00171, -0.2], until=[0.05], workers=1)
