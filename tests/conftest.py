"""Shared test configuration: pytester, and the test groups.

Groups are markers (registered in pyproject.toml), given here by file or test name
so the test files stay about what they check:

- ``slow``: more than a few seconds on an idle 2-core machine (hypothesis searches,
  pytester runs under xdist, flights to battery depletion, JIT compiles, packaging);
  ``pytest tests -m "not slow" -n 2`` is the inner loop.
- ``jax``: needs the ``[mjx]`` extra; CI's newest-versions stage must not skip them:
  with ``FLOCKAI_REQUIRE_JAX=1`` (.ci/run) a skipped ``jax`` test fails, and JAX
  missing is a usage error.
- ``browser``: drives headless Chromium.
"""

import importlib
import os

import pytest

pytest_plugins = ["pytester"]

#: CI's newest-versions stage sets this: a jax test that skips is then a failure
REQUIRE_JAX = os.environ.get("FLOCKAI_REQUIRE_JAX") == "1"

# ``import pytest_flockai`` is lazy (PEP 562), so the first flight of a session may happen
# inside a pytester in-process run; pytester then drops the modules that run imported, and the
# next run imports numpy's C extension a second time ("cannot load module more than once per
# process", or an abort). The C extensions the flights use are imported here, once, first.
for _name in ("numpy", "pandas", "mujoco", "cv2", "onnxruntime", "matplotlib.pyplot",
              "pytest_flockai.mission", "pytest_flockai.ml", "pytest_flockai.fleet",
              "pytest_flockai.sweeps", "pytest_flockai.plots"):
    try:
        if _name == "matplotlib.pyplot":
            importlib.import_module("matplotlib").use("Agg")
        importlib.import_module(_name)
    except ImportError:
        pass

#: whole files whose every test is slow
SLOW_FILES = {"test_sweep_mjx.py", "test_sweep_batched.py", "test_interrupted_runs.py",
              "test_packaging.py", "test_baseline_gate.py", "test_fuzz.py",
              "test_sweep_cluster.py", "test_sweep_failures.py"}
#: single slow tests, by function name (all their parametrizations)
SLOW_TESTS = {
    "test_hypothesis_finds_wind_breaking_a_flight_time_budget",
    "test_hypothesis_finds_and_shrinks_a_failing_condition",
    "test_the_robustness_search_finds_the_haze",
    "test_the_hypothesis_example_shrinks_to_the_boundary",
    "test_xdist_workers_share_the_cache",
    "test_xdist_reports_equal_the_serial_ones",
    "test_every_readme_example_runs",
    "test_mavic_25kmh_until_depleted_lasts_31_min_and_beats_hover",
    "test_mavic_hover_until_depleted_lasts_29_min",
    "test_crazyflie_hover_about_7_min",
    "test_hypothesis_examples_are_recorded_compactly",
    "test_four_drones_cover_an_area_in_a_quarter_of_one_drones_time",
    "test_onboard_costs_processing_energy_and_flight_time",
    "test_recall_falls_with_haze_and_with_blur",
    "test_blur_length_is_speed_times_exposure_times_focal_over_altitude",
    "test_the_tutorial_test_file_passes_under_pytest",
    "test_the_readme_test_file_passes_under_pytest",
    "test_modeled_latency_identical_measured_reports_spread",
    "test_a_warm_sweep_reads_every_variant_and_starts_no_worker",
    "test_same_dataframe_with_one_or_two_worker_processes",
    "test_remote_task_latency_grows_with_the_fleet_on_a_shared_link",
    "test_the_dashboard_in_a_headless_browser",
    "test_the_example_suite_dashboard_at_1280_px",
    "test_cruise_beats_hover_on_a_small_folding_drone",
    "test_the_wheel_carries_the_shipped_models",
    "test_a_slow_radio_degrades_the_loop",
    "test_lands_on_the_marker",
    "test_jax_and_the_core_agree_on_end_reasons_over_wind_payload_and_seed",
    "test_mjx_and_the_core_agree_on_end_reasons_in_extreme_wind_at_the_payload_limit",
    "test_jax_sees_the_crashes_of_a_crazyflie_in_strong_wind",
    "test_a_repeated_sweep_reuses_its_variants_and_a_changed_base_does_not",
}
JAX_FILES = {"test_sweep_mjx.py"}
BROWSER_TESTS = {"test_the_dashboard_in_a_headless_browser",
                 "test_the_worst_frames_are_in_the_dashboard_with_boxes_on_the_right_objects",
                 "test_the_example_suite_dashboard_at_1280_px"}


def pytest_collection_modifyitems(items):
    for item in items:
        fname = item.path.name
        func = getattr(item, "originalname", item.name)
        if fname in SLOW_FILES or func in SLOW_TESTS:
            item.add_marker(pytest.mark.slow)
        if fname in JAX_FILES:
            item.add_marker(pytest.mark.jax)
        if func in BROWSER_TESTS or "headless_browser" in func:
            item.add_marker(pytest.mark.browser)
        if func.startswith("test_every_docs_example_runs") and "imaging-conditions" in item.name:
            item.add_marker(pytest.mark.slow)


def pytest_sessionstart(session):
    if REQUIRE_JAX:
        try:
            import jax  # noqa: F401
            import mujoco.mjx  # noqa: F401
        except ImportError as exc:
            raise pytest.UsageError(f"FLOCKAI_REQUIRE_JAX=1 but JAX/MJX do not import ({exc}): "
                                    f"the jax-marked tests would skip") from None


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    rep = outcome.get_result()
    if REQUIRE_JAX and rep.skipped and item.get_closest_marker("jax") is not None:
        rep.outcome = "failed"
        rep.longrepr = f"FLOCKAI_REQUIRE_JAX=1: a jax-marked test skipped: {rep.longrepr}"
