"""The stepping order of a drone's components is one table (mission/steps.py
STEP_ORDER): the flight is built from it and the docs print it."""

import re
from pathlib import Path

import pytest

import pytest_flockai as fa
from pytest_flockai.mission.assemble import Flight
from pytest_flockai.mission.plan import resolve
from pytest_flockai.mission.steps import STEP_KEYS, STEP_ORDER, ordered

ROOT = Path(__file__).resolve().parents[2]


class Mark(fa.Clocked):
    def step(self, t):
        pass


def test_a_flight_with_every_step_is_built_in_the_table_order():
    m = fa.Mission(fa.drone("crazyflie-2-1"), fa.pilots.Hover(1.0, 1.0), wind=2.0,
                   fly_on="estimate", components=[Mark()], max_wall_s=60.0,
                   policies=[fa.policy.Rule("time_s >= 25", [fa.policy.Hold()], name="late")])
    run = Flight([resolve(m)], [m]).runs[0]
    by_class = {s.component: s.key for s in STEP_ORDER}
    keys = [by_class.get(type(c).__name__, "components" if isinstance(c, Mark) else "policies")
            for c in run.components]
    assert keys == [k for k in STEP_KEYS if k in keys]          # the table's order
    assert set(STEP_KEYS) - set(keys) == {"tasks"}              # every step but tasks here


def test_a_component_without_a_row_is_refused():
    assert ordered({"end": ["e"], "sensing": ["s"]}) == ["s", "e"]
    with pytest.raises(ValueError, match=r"\['radar'\] have no row in STEP_ORDER"):
        ordered({"radar": ["r"]})


def test_the_docs_print_the_table_not_a_copy():
    page = (ROOT / "docs" / "explanation" / "flight-path.md").read_text()
    assert "<!-- gen:step_order -->" in page
    for s in STEP_ORDER:      # no hand-written row of the table left on any page
        for p in (ROOT / "docs").rglob("*.md"):
            assert not re.search(rf"^\| *\d+ *\| *`{s.component}`", p.read_text(), re.M), p
