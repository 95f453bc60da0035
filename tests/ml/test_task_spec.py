"""A Task is a frozen spec like a Mission: keyword-only after the model, checked once
when built, changed only through a copy (``replace``) that is checked again. A policy's
task action (``set_period``, ``set_model``, ``set_execution``) flies on such a copy."""

import dataclasses
import pickle

import pytest

import pytest_flockai as fa
from pytest_flockai.errors import ConfigError


def nobody(frame):
    return 0


def model(**kw):
    return fa.ml.PythonModel(nobody, macs=1e6, name="count", **kw)


def task(**kw):
    return fa.Task(model(), **kw)


@pytest.mark.parametrize("field, value", [("period_s", -1.0), ("execution", "remot"),
                                          ("name", "other"), ("jpeg_quality", 101)])
def test_a_field_cannot_be_assigned_after_the_checks(field, value):
    t = task()
    with pytest.raises(dataclasses.FrozenInstanceError, match=f"'{field}'"):
        setattr(t, field, value)
    assert getattr(t, field) == getattr(task(), field)


@pytest.mark.parametrize("replace", [lambda t, **c: t.replace(**c), dataclasses.replace])
@pytest.mark.parametrize("changes, message", [
    ({"period_s": -1}, r"task 'count': period_s = -1 is out of range; allowed: > 0"),
    ({"period_s": 1e-6}, r"period_s = 1e-06"),
    ({"execution": "remot"}, r"execution = 'remot' is not allowed"),
    ({"jpeg_quality": 101}, r"jpeg_quality = 101 is not allowed; expected an int >= 0 and <= 100"),
    ({"link": "wifu"}, r"link = 'wifu' is not a known link"),
    ({"name": "a.b"}, r"name = 'a.b' is not allowed"),
    ({"score_threshold": 1.5}, r"score_threshold = 1.5 is out of range"),
])
def test_a_changed_copy_is_checked_again(replace, changes, message):
    with pytest.raises(ConfigError, match=message):
        replace(task(), **changes)


def test_replace_names_an_unknown_field():
    with pytest.raises(ConfigError, match=r"Task.replace: period is not a Task field.*period_s"):
        task().replace(period=1.0)


def test_arguments_after_the_model_are_keyword_only():
    with pytest.raises(TypeError, match="positional"):
        fa.Task(model(), "camera", 2.0)                # type: ignore[misc]


def test_a_copy_is_the_task_built_with_its_values():
    t = task(execution="remote", link="lte", jpeg_quality=70)
    copy = t.replace(period_s=2.0)
    assert copy is not t and t.period_s == 5.0
    assert copy.to_dict() == task(execution="remote", link="lte", jpeg_quality=70,
                                  period_s=2.0).to_dict()
    assert copy.model is t.model and copy.name == "count"     # the model is shared, not copied
    assert pickle.loads(pickle.dumps(t.replace(count=None))).to_dict() == t.to_dict()


def test_a_policy_changes_a_copy_and_the_missions_task_is_untouched():
    eye = fa.Task(fa.ml.Oracle(classes=["person"]), period_s=0.5, name="eye")
    speed_up = fa.policy.Rule("time_s >= 12", [fa.policy.SetPeriod("eye", 0.1)], name="fast",
                              once=True, period_s=1.0)
    m = fa.Mission(fa.drone("dji-mavic-2-pro"), fa.pilots.Hover(altitude=15.0),
                   world=fa.World.scene(people=[(0.0, 0.0)], size=(40.0, 40.0)), tasks=[eye],
                   policies=[speed_up], until=20.0)
    res = m.run()
    frames = [e["t_capture"] for e in res.events if e["kind"] == "inference"]
    assert sum(1 for t in frames if 10.0 <= t < 11.99) == 4             # 2 Hz (in the air at ~9 s)
    assert sum(1 for t in frames if 12.05 < t < 19.95) == 79            # 10 Hz after the rule
    assert m.tasks[0] is eye and eye.period_s == 0.5
