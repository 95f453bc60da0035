"""Shared test configuration: pytester, and the test groups.

Groups are markers (registered in pyproject.toml), given here by file or test name
so the test files stay about what they check:

- ``slow``: more than a few seconds on an idle 2-core machine (hypothesis searches,
  pytester runs under xdist, flights to battery depletion, JIT compiles, packaging);
  ``pytest tests -m "not slow" -n 2`` is the inner loop.
- ``jax``: needs the ``[mjx]`` extra; CI's newest-versions stage must not skip them.
- ``browser``: drives headless Chromium.
"""

import pytest

pytest_plugins = ["pytester"]

#: whole files whose every test is slow
SLOW_FILES = {"test_sweep_mjx.py", "test_interrupted_runs.py", "test_packaging.py",
              "test_baseline_gate.py", "test_fuzz.py"}
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
    "test_modeled_latency_identical_measured_reports_spread",
    "test_a_warm_sweep_reads_every_variant_and_starts_no_worker",
    "test_same_dataframe_with_one_or_two_worker_processes",
    "test_remote_task_latency_grows_with_the_fleet_on_a_shared_link",
    "test_the_dashboard_in_a_headless_browser",
}
JAX_FILES = {"test_sweep_mjx.py"}
BROWSER_TESTS = {"test_the_dashboard_in_a_headless_browser"}


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
