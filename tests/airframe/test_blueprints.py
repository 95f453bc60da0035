import math

import pytest

import pytest_flockai as fa
from pytest_flockai import ConfigError


def test_builtin_blueprints_listed_and_loadable():
    names = fa.blueprints()
    assert {"dji-mavic-2-pro", "crazyflie-2-1", "generic-hexa-680"} <= set(names)
    for n in names:
        d = fa.drone(n)
        assert d.name == n
        assert d.thrust_to_weight >= 1.3


def test_mavic_numbers_from_spec():
    d = fa.drone("dji-mavic-2-pro")
    assert d.airframe.mass_kg == pytest.approx(0.907)
    assert d.battery.capacity_mah == 3850 and d.battery.voltage_v == 15.4
    assert d.battery.nameplate_wh == pytest.approx(59.29, rel=1e-3)
    assert d.rotor.diameter_m == pytest.approx(0.221)
    assert 2 * d.airframe.arm_length_m == pytest.approx(0.354)


def test_drones_are_fresh_and_independent():
    a, b = fa.drone("dji-mavic-2-pro"), fa.drone("dji-mavic-2-pro")
    a.battery.capacity_mah = 4500
    a.payload_kg = 0.2
    assert b.battery.capacity_mah == 3850 and b.payload_kg == 0
    assert a.mass_kg == pytest.approx(1.107)


def test_overrides():
    d = fa.drone("dji-mavic-2-pro", battery_mah=4500, payload_kg=0.2, usable_fraction=0.9)
    assert d.battery.capacity_mah == 4500 and d.payload_kg == 0.2 and d.battery.usable_fraction == 0.9
    with pytest.raises(ConfigError, match="battery_mha.*did you mean"):
        fa.drone("dji-mavic-2-pro", battery_mha=4500)


def test_unknown_blueprint_lists_names_and_close_match():
    with pytest.raises(ConfigError) as e:
        fa.drone("dji-mavic-2")
    msg = str(e.value)
    assert "dji-mavic-2-pro" in msg and "crazyflie-2-1" in msg and "did you mean" in msg


@pytest.mark.parametrize("value", [-1.0, 0.0, float("nan")])
def test_bad_mass_names_file_field_value(tmp_path, value):
    from importlib import resources
    text = (resources.files("pytest_flockai.airframe") / "blueprints" / "crazyflie-2-1.toml").read_text()
    bad = text.replace("mass_kg = 0.027", f"mass_kg = {'nan' if math.isnan(value) else value}")
    p = tmp_path / "bad.toml"
    p.write_text(bad)
    with pytest.raises(ConfigError) as e:
        fa.drone(str(p))
    msg = str(e.value)
    assert "bad.toml" in msg and "mass_kg" in msg


def _cf_text():
    from importlib import resources
    return (resources.files("pytest_flockai.airframe") / "blueprints" / "crazyflie-2-1.toml").read_text()


def test_unknown_key_and_missing_field(tmp_path):
    p = tmp_path / "typo.toml"
    p.write_text(_cf_text().replace("arm_length_m", "arm_lenght_m"))
    with pytest.raises(ConfigError, match=r"typo.toml \[airframe\].*unknown key 'arm_lenght_m'.*did you mean"):
        fa.drone(str(p))
    p2 = tmp_path / "missing.toml"
    p2.write_text(_cf_text().replace("diameter_m = 0.0462", ""))
    with pytest.raises(ConfigError, match=r"missing.toml \[rotor\].*missing field 'diameter_m'"):
        fa.drone(str(p2))


def test_thrust_to_weight_below_minimum(tmp_path):
    p = tmp_path / "weak.toml"
    p.write_text(_cf_text().replace("max_speed_rad_s = 2274.0", "max_speed_rad_s = 1700.0"))
    with pytest.raises(ConfigError, match=r"weak.toml.*thrust-to-weight = 1\.26"):
        fa.drone(str(p))
    # payload that makes it too heavy is refused before flying
    d = fa.drone("crazyflie-2-1")
    d.payload_kg = 0.03
    with pytest.raises(ConfigError, match="thrust-to-weight"):
        fa.Mission(d, fa.pilots.Hover(1.0, 1.0)).run()


def test_bad_toml_and_missing_file(tmp_path):
    p = tmp_path / "broken.toml"
    p.write_text("name = \n")
    with pytest.raises(ConfigError, match="not valid TOML"):
        fa.drone(str(p))
    with pytest.raises(ConfigError, match="does not exist"):
        fa.drone(str(tmp_path / "nope.toml"))


def test_assignment_is_validated_where_it_enters():
    d = fa.drone("dji-mavic-2-pro")
    with pytest.raises(ConfigError, match=r"capacity_mah = -5"):
        d.battery.capacity_mah = -5
    with pytest.raises(ConfigError, match="usable_fraction"):
        d.battery.usable_fraction = 1.5
    with pytest.raises(ConfigError, match="reserve_fraction"):
        d.battery.reserve_fraction = 1.0
    with pytest.raises(ConfigError, match="payload_kg"):
        d.payload_kg = -0.1
    with pytest.raises(ConfigError, match="unknown field 'capacity'"):
        d.battery.capacity = 10


def test_user_blueprint_file_roundtrip(tmp_path):
    p = tmp_path / "my-drone.toml"
    p.write_text(_cf_text().replace('name = "crazyflie-2-1"', 'name = "my-drone"'))
    d = fa.drone(str(p))
    assert d.name == "my-drone" and d.source == str(p)
