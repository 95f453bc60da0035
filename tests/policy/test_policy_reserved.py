"""A Policy subclass storing data under a name the flight loop calls
(``self.step``, ``self.kpis``, ``self.finish``) is a ConfigError where it is written,
not a raw TypeError in the loop; the policies as flown are ``result.policies[name]``."""

import pickle

import pytest

import pytest_flockai as fa
from pytest_flockai.errors import ConfigError


@pytest.mark.parametrize("attr", ["step", "kpis", "finish", "bind", "to_dict"])
def test_storing_data_under_a_reserved_name_is_refused_at_construction(attr):
    class Saver(fa.Policy):
        def __init__(self):
            super().__init__(name="saver")
            setattr(self, attr, 0)

        def decide(self, t, drone):
            pass

    with pytest.raises(ConfigError, match=rf"self\.{attr} = 0 is not allowed: '{attr}' is a "
                                          rf"reserved name of fa.Policy.*reserved: .*step"):
        Saver()


def test_a_class_attribute_under_a_reserved_name_is_refused():
    with pytest.raises(ConfigError, match=r"class Bad: kpis = \{\} is not allowed"):
        class Bad(fa.Policy):
            kpis = {}


def test_overriding_a_reserved_method_is_still_allowed():
    class Mine(fa.Policy):
        def step(self, t):
            super().step(t)

        def decide(self, t, drone):
            pass

    Mine(name="mine").count = 1


class Counter(fa.Policy):
    def __init__(self):
        super().__init__(name="counter", period_s=1.0)
        self.calls = 0

    def decide(self, t, drone):
        self.calls += 1
        self.last_battery = drone.battery


def test_the_flown_policy_is_in_the_result_and_the_one_passed_is_untouched():
    mine = Counter()
    r = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(altitude=1.0, duration=3.0),
                   policies=[mine], until=5.0).run()
    flown = r.policies["counter"]
    assert flown is not mine and isinstance(flown, Counter)
    assert flown.calls == 6 and 0 < flown.last_battery < 1      # t = 0, 1, ..., 5 s
    assert mine.calls == 0 and not hasattr(mine, "last_battery")
    # pickled (a sweep's worker) without them: they hold the flight
    assert dict(pickle.loads(pickle.dumps(r)).policies) == {}
