"""Latency on device profiles: modeled (deterministic) and measured (calibrated)."""

import numpy as np
import pytest

from pytest_flockai.compute.devices import device
from pytest_flockai.compute.latency import (
    calibrate,
    measured_latency,
    modeled_latency,
    scale_to_device,
)
from pytest_flockai.errors import ConfigError


def test_modeled_latency_is_the_formula_and_deterministic():
    rpi = device("raspberry-pi-4")
    want = rpi.overhead_s + 3e8 / rpi.macs_per_s
    runs = {modeled_latency(3e8, "raspberry-pi-4") for _ in range(5)}
    assert runs == {want}
    assert modeled_latency(3e8, rpi) == want
    assert modeled_latency(0, "jetson-orin-nano") == device("jetson-orin-nano").overhead_s
    # faster device, lower latency
    assert modeled_latency(3e8, "jetson-orin-nano") < modeled_latency(3e8, "jetson-nano-5w") < want


@pytest.mark.parametrize("bad", [None, -1, float("nan"), "many", True])
def test_modeled_latency_rejects_bad_macs(bad):
    with pytest.raises(ConfigError, match="macs"):
        modeled_latency(bad, "raspberry-pi-4")


def test_unknown_device_names_close_match():
    with pytest.raises(ConfigError, match="raspberry-pi-4"):
        modeled_latency(1, "raspberry-pi4")


def test_calibration_is_cached_and_scales_to_devices():
    cal = calibrate()
    assert calibrate() is cal
    assert cal.host_macs_per_s > 1e8 and cal.runs >= 3
    assert cal.p10_s <= cal.median_s <= cal.p90_s and cal.spread >= 0
    # the calibration net itself gets its modeled latency, by construction
    rpi = device("raspberry-pi-4")
    assert scale_to_device(cal.median_s, rpi, cal) == pytest.approx(
        modeled_latency(cal.macs, rpi))
    out, secs, wall = measured_latency(np.add, 1, 2, device=rpi)
    assert out == 3 and secs >= rpi.overhead_s and wall >= 0
