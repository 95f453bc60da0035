"""Policies: your own decide(t, drone), the actions on tasks and on the flight plan, and
the clear errors for what a policy cannot name or do."""

import math

import pytest

import pytest_flockai as fa
from pytest_flockai.errors import ConfigError


def oracle_task(**kw):
    return fa.Task(fa.ml.Oracle(classes=["person"], **kw), period_s=0.5, evaluate="detection",
                   name="eye")


def mission(policies=(), *, tasks=None, actors=(), until=40.0, world=None, pilot=None):
    return fa.Mission(fa.drone("dji-mavic-2-pro"), pilot or fa.pilots.Hover(altitude=15.0),
                      world=world or fa.World.scene(people=[(0.0, 0.0)], size=(200.0, 200.0)),
                      tasks=[oracle_task()] if tasks is None else tasks, actors=actors,
                      policies=policies, until=until)


class Scripted(fa.Policy):
    """At given times, do given things; remember what the drone knew."""

    def __init__(self, script, **kw):
        super().__init__(**kw)
        self.script = script

    def start(self, run):
        self.done = set()
        self.seen = []

    def decide(self, t, drone):
        for r in drone.results("eye"):
            self.seen.append((r.t_capture, r.t_delivered, len(r.detections)))
        for i, (at, fn) in enumerate(self.script):
            if t >= at and i not in self.done:
                self.done.add(i)
                fn(drone)


def events(res, kind="policy"):
    return [e for e in res.events if e["kind"] == kind]


def test_task_actions_change_the_workload():
    pol = Scripted([(20.0, lambda d: d.set_period("eye", 0.1)),
                    (30.0, lambda d: d.disable("eye")),
                    (35.0, lambda d: d.enable("eye"))])
    res = mission([pol]).run()
    frames = [e["t_capture"] for e in res.events if e["kind"] == "inference"]
    assert sum(1 for t in frames if 10.25 < t < 19.75) == 19          # 2 Hz
    assert sum(1 for t in frames if 20.25 < t < 29.75) == 95          # 10 Hz
    assert not [t for t in frames if 30.15 < t < 35.0]                # off
    assert sum(1 for t in frames if t >= 35.0) >= 40
    assert [e["action"] for e in events(res)] == ["set_period", "disable", "enable"]
    assert res.kpis["policy.scripted.triggers"] == 3


def test_results_arrive_when_delivered_not_when_captured():
    lag = fa.policy.Rule("eye.latency_s > 0.6", [fa.policy.Hold()], name="lag", period_s=0.1)
    res = mission([lag], tasks=[oracle_task(delay_s=0.7)]).run()
    first_capture = min(e["t_capture"] for e in res.events if e["kind"] == "inference")
    hold = events(res)[0]
    assert hold["action"] == "hold"
    assert first_capture + 0.7 <= hold["t"] < first_capture + 0.7 + 0.11


def test_plan_actions_fly_the_drone_and_resume_the_survey():
    survey = fa.pilots.Waypoints([(0.0, 0.0, 15.0), (60.0, 0.0, 15.0), (60.0, 60.0, 15.0)],
                                 speed=5.0)
    pol = Scripted([(15.0, lambda d: d.goto(-40.0, -30.0, 20.0)),
                    (35.0, lambda d: d.resume())])
    res = mission([pol], pilot=survey, until=120.0).run()
    tel = res.telemetry
    x, y, z = tel[["x", "y", "z"]].asof(34.0)
    assert math.dist((x, y), (-40.0, -30.0)) < 1.0 and abs(z - 20.0) < 0.5
    # back on the survey: it reaches the plan's last point, then returns home and lands
    assert min(math.dist(p, (60.0, 60.0)) for p in tel[["x", "y"]].to_numpy()) < 1.0
    assert res.end_reason == "landed"
    assert [e["action"] for e in events(res)] == ["goto", "resume"]


def test_land_and_return_home_end_the_flight_early():
    res = mission([Scripted([(15.0, lambda d: d.land())])], until=120.0).run()
    assert res.end_reason == "landed" and res.kpis["flight_time_s"] < 40.0
    far = fa.pilots.Waypoints([(80.0, 0.0, 15.0)], speed=5.0)
    res = mission([Scripted([(20.0, lambda d: d.return_home())])], pilot=far, until=200.0).run()
    stages = [e["stage"] for e in res.events if e["kind"] == "stage"]
    assert stages[:3] == ["takeoff", "pilot", "return"] and res.end_reason == "landed"


def test_a_plan_action_outside_the_pilot_stage_is_refused():
    res = mission([Scripted([(1.0, lambda d: d.goto(10.0, 10.0))])], until=20.0).run()
    refused = events(res, "policy_refused")
    assert refused and refused[0]["action"] == "goto" and refused[0]["stage"] == "takeoff"
    assert events(res) == []


def test_two_alternating_refused_actions_are_logged_once_each():
    class Nag(fa.Policy):
        def decide(self, t, drone):
            drone.goto(10.0, 10.0)
            drone.hold()

    res = mission([Nag(period_s=0.05)], until=3.0).run()
    refused = [(e["action"], e["stage"]) for e in events(res, "policy_refused")]
    assert refused == [("goto", "takeoff"), ("hold", "takeoff")]


def test_modes_are_timed():
    rule = fa.policy.Rule("time_s >= 25", [fa.policy.Hold()], name="late", period_s=0.5)
    res = mission([rule]).run()
    k = res.kpis
    assert k["policy.late.time_idle_s"] == pytest.approx(25.0, abs=0.01)
    assert k["policy.late.time_active_s"] == pytest.approx(k["flight_time_s"] - 25.0, abs=0.1)
    assert fa.kpis.get("policy.late.time_active_s").unit == "s"


@pytest.mark.parametrize("policy, words", [
    (lambda: fa.policy.Rule("battery < 0.4", [fa.policy.SetPeriod("eyes", 2.0)]),
     ["'eyes'", "not a task of the mission", "did you mean", "'eye'"]),
    (lambda: fa.policy.Rule("batery < 0.4", [fa.policy.Hold()]),
     ["signal 'batery'", "did you mean", "battery", "eye.count"]),
    (lambda: fa.policy.Rule("cam.count > 3", [fa.policy.Hold()]), ["signal 'cam.count'"]),
    (lambda: fa.policy.Rule("battery < 0.4", [fa.policy.SetExecution("eye", "remote")]),
     ["cannot take", "reads the truth"]),
    (lambda: fa.policy.Follow("detector"), ["task = 'detector'", "allowed: 'eye'"]),
    (lambda: fa.policy.Follow("eye", target="vehicle"), ["target = 'vehicle'", "'person'"]),
    (lambda: fa.policy.Follow("eye", score="bob"), ["score = 'bob'", "not an actor"]),
])
def test_a_policy_naming_what_the_mission_lacks_is_refused(policy, words):
    with pytest.raises(ConfigError) as e:
        mission([policy()])
    for w in words:
        assert w in str(e.value)


@pytest.mark.parametrize("build, words", [
    (lambda: fa.policy.Rule("battery is low", []), ["when = 'battery is low'", "<signal> <op>"]),
    (lambda: fa.policy.GoTo(0.0, 0.0, -5.0), ["z = -5.0"]),
    (lambda: fa.policy.Rule("battery < 0.4", ["land"]), ["then[0] = 'land' is not an action"]),
    (lambda: fa.policy.Follow("eye", on_lost="panic"), ["on_lost = 'panic'", "'search'"]),
    (lambda: fa.ml.Oracle(miss_rate=1.5), ["miss_rate = 1.5"]),
    (lambda: fa.Task(fa.ml.Oracle(), execution="remote"), ["execution = 'remote'", "delay_s"]),
    (lambda: fa.actors.Person([(0.0, 0.0)], speed=-1.0), ["speed = -1.0"]),
])
def test_bad_policy_and_actor_arguments(build, words):
    with pytest.raises(ConfigError) as e:
        build()
    for w in words:
        assert w in str(e.value)


def test_policy_list_errors():
    with pytest.raises(ConfigError, match="policies\\[0\\] = 'land' is not a Policy"):
        mission(["land"])
    with pytest.raises(ConfigError, match="two policies are named 'rule'"):
        mission([fa.policy.Rule("battery < 0.5", []), fa.policy.Rule("battery < 0.2", [])])


def test_an_actor_path_outside_the_world_is_refused():
    stray = fa.actors.Person([(0.0, 0.0), (30.0, 0.0), (30.0, 120.0)], name="stray")
    with pytest.raises(ConfigError) as e:
        mission(actors=[stray])
    assert "path[2] = (30, 120) is outside the world" in str(e.value)
    assert "|y| <= 100 m" in str(e.value)


def test_with_fly_on_estimate_the_policy_sees_the_estimate():
    """The position a policy reads, and the pose it projects boxes with, is the GPS and
    barometer estimate the drone flies on: it differs from the truth by the sensors' noise."""
    got = []

    class Look(fa.Policy):
        def decide(self, t, drone):
            st = drone._st
            got.append((drone.position, tuple(st.qc[:3]), tuple(st.q[:3])))
            for r in drone.results("eye"):
                got.append(("nav", r.nav))

    m = fa.Mission(fa.drone("dji-mavic-2-pro"), fa.pilots.Hover(altitude=15.0),
                   world=fa.World.scene(people=[(0.0, 0.0)]), tasks=[oracle_task()],
                   policies=[Look(name="look", period_s=1.0)], fly_on="estimate", until=30.0)
    m.run()
    poses = [g for g in got if g[0] != "nav"]
    assert all(seen == est for seen, est, _ in poses)
    assert max(math.dist(seen, true) for seen, _, true in poses[5:]) > 0.05
    navs = [g[1] for g in got if g[0] == "nav"]
    assert navs and all(n is not None for n in navs)


def test_a_rule_on_a_probe_metric_and_no_truth_probes():
    busy = fa.policy.Rule("compute.cpu_utilization >= 0.0", [fa.policy.SetPeriod("eye", 1.0)],
                          name="busy", once=True, period_s=1.0)
    res = mission([busy], until=25.0).run()
    acts = [e for e in res.events if e["kind"] == "policy"]
    assert [a["action"] for a in acts] == ["set_period"]
    assert acts[0]["t"] >= 1.0          # the compute probe's first sample is one period in
    with pytest.raises(ConfigError, match="signal 'ml.detection_recall'"):
        mission([fa.policy.Rule("ml.detection_recall < 0.5", [fa.policy.Hold()])])
