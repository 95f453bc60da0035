"""Every Python example in the README runs, top to bottom in one namespace, as a
reader would paste them; the tests they define are called too."""

import os
import re
from pathlib import Path

import pytest

import pytest_flockai as fa

ROOT = Path(__file__).resolve().parent.parent
BLOCKS = re.findall(r"```python\n(.*?)```", (ROOT / "README.md").read_text(), re.S)


@pytest.fixture(scope="module")
def readme_namespace():
    cwd = os.getcwd()
    os.chdir(ROOT)                     # the examples use paths relative to the repository
    ns: dict = {"__name__": "readme"}
    try:
        for i, block in enumerate(BLOCKS):
            try:
                exec(compile(block, f"README.md python block {i}", "exec"), ns)
            except Exception as exc:
                pytest.fail(f"README python block {i} fails: {type(exc).__name__}: {exc}\n{block}")
    finally:
        os.chdir(cwd)
    return ns


def test_the_readme_has_examples():
    assert len(BLOCKS) >= 6


def test_every_readme_example_runs(readme_namespace):
    ns = readme_namespace
    assert ns["r"].end_reason == "geofence"                  # the last block: the geofence
    ns["test_what_if_bigger_battery"]()                       # "A test in 20 lines"


def test_the_readme_hypothesis_example_fails_on_a_short_battery(readme_namespace):
    """The README's hypothesis test, body run on two of its examples (the whole
    search with shrinking flies about 300 missions): a 3000 mAh battery cannot hover
    24 min (29 min x 3000/3850 = 22.6 min), a 4500 mAh one can."""
    body = readme_namespace["test_flight_time_holds"].hypothesis.inner_test
    body(wind=fa.Wind((2.0, 0.0, 0.0)), mah=4500)
    with pytest.raises(AssertionError, match="endurance_s"):
        body(wind=fa.Wind((2.0, 0.0, 0.0)), mah=3000)


def test_the_readme_robustness_search_finds_the_haze(readme_namespace):
    """The README's hypothesis search over imaging conditions breaks the 0.5 recall
    budget (the shipped detector fails in haze) and reports the shrunk example."""
    with pytest.raises(AssertionError, match="recall"):
        readme_namespace["test_detector_recall_holds"]()
