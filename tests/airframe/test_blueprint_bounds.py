"""Physical-plausibility bounds on blueprint fields: a unit slip is
refused where it enters, naming the file, the field, what is allowed and why."""

import importlib.resources as res

import pytest

import pytest_flockai as fa
from pytest_flockai.errors import ConfigError


def _mavic_text():
    return (res.files("pytest_flockai.airframe") / "blueprints" / "dji-mavic-2-pro.toml").read_text()


@pytest.mark.parametrize("old, new, field, why", [
    ("diameter_m = 0.221", "diameter_m = 22.1", "diameter_m", "propellers"),
    ("arm_length_m = 0.177", "arm_length_m = 177", "arm_length_m", "rotor axis"),
    ("capacity_mah = 3850.0", "capacity_mah = 3.85", "capacity_mah", "mAh"),
    ("time_constant_s = 0.030", "time_constant_s = 30", "time_constant_s", "spin-up"),
    ("max_speed_rad_s = 827.0", "max_speed_rad_s = 7900", None, None),     # 7900 rad/s is plausible
    ("control_hz = 50.0", "control_hz = 0.5", "control_hz", "loop rates"),
    ("mass_kg = 0.907                 # spec", "mass_kg = 907 # spec", "mass_kg", "drone"),
])
def test_implausible_fields_are_refused_with_the_reason(tmp_path, old, new, field, why):
    text = _mavic_text()
    assert old in text, old
    p = tmp_path / "mine.toml"
    p.write_text(text.replace(old, new, 1))
    if field is None:
        fa.drone(str(p))
        return
    with pytest.raises(ConfigError) as e:
        fa.drone(str(p))
    msg = str(e.value)
    assert "mine.toml" in msg and field in msg and "physically plausible" in msg and why in msg, msg


def test_a_unit_slip_in_code_is_refused_too():
    d = fa.drone("crazyflie-2-1")
    with pytest.raises(ConfigError, match="rad/s, not rpm"):
        d.rotor.max_speed_rad_s = 21700.0        # rpm, not rad/s


def test_sensor_names_given_as_a_string_are_refused_not_read_as_characters(tmp_path):
    p = tmp_path / "cf.toml"
    text = (res.files("pytest_flockai.airframe") / "blueprints" / "crazyflie-2-1.toml").read_text()
    p.write_text(text.replace('names = ["imu", "barometer", "battery"]', 'names = "gps"'))
    with pytest.raises(ConfigError) as e:
        fa.drone(str(p))
    msg = str(e.value)
    assert "cf.toml [sensors]" in msg and "names = 'gps'" in msg and "list" in msg, msg
