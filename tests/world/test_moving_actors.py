"""Moving people and cars: where they are is a function of time and the seed; every
frame's per-object truth holds them there, and a rendered frame shows them there."""

import math

import numpy as np
import pytest

import pytest_flockai as fa
from pytest_flockai.control.tracking import ground_point
from pytest_flockai.world.actors import WALK_SPEED


def test_a_scripted_walker_walks_60_m_and_turns():
    p = fa.actors.walk_and_turn(start=(0.0, 0.0), heading_deg=0.0, first_m=60.0, turn_deg=90.0,
                                then_m=40.0, start_s=5.0)
    assert p.speed == WALK_SPEED == 1.4
    assert p.at(0.0) == (0.0, 0.0, 0.0)                     # waits for start_s
    x, y, h = p.at(5.0 + 59.0 / 1.4)
    assert (x, y) == pytest.approx((59.0, 0.0)) and h == pytest.approx(0.0)
    x, y, h = p.at(5.0 + 80.0 / 1.4)
    assert (x, y) == pytest.approx((60.0, 20.0)) and h == pytest.approx(math.pi / 2)
    assert p.at(1e4)[:2] == pytest.approx((60.0, 40.0))     # stays at the end


def test_loop_walks_back_and_forth():
    p = fa.actors.Person([(0.0, 0.0), (10.0, 0.0)], speed=1.0, loop=True)
    assert p.at(15.0)[:2] == pytest.approx((5.0, 0.0)) and abs(p.at(15.0)[2]) == pytest.approx(math.pi)
    assert p.at(25.0)[:2] == pytest.approx((5.0, 0.0)) and p.at(25.0)[2] == pytest.approx(0.0)


def test_walkers_and_traffic_come_from_the_seed():
    area = ((-50.0, -50.0), (50.0, 50.0))
    a, b = fa.actors.walkers(5, area, seed=1), fa.actors.walkers(5, area, seed=1)
    assert [w.path for w in a] == [w.path for w in b]
    assert [w.path for w in a] != [w.path for w in fa.actors.walkers(5, area, seed=2)]
    assert all(1.26 <= w.speed <= 1.54 for w in a)
    city = fa.World.urban(seed=1, size=(200.0, 200.0), people=0)
    cars = fa.actors.traffic(city, 6, seed=3)
    for car in cars:
        for t in np.linspace(0.0, 60.0, 13):
            x, y, _ = car.at(t)
            assert any(x0 <= x <= x1 and y0 <= y <= y1 for x0, y0, x1, y1 in city.streets)


class Spy(fa.Clocked):
    """Reads the camera at given times: its truth (and, with render=True, the frame)."""

    def __init__(self, times, render=False):
        self.times, self.render = list(times), render
        self.seen = []

    def bind(self, run):
        super().bind(run)
        self.run, self.cam, self.seen = run, run.suite["camera"], []
        self._todo = list(self.times)

    def step(self, t):
        if self._todo and t >= self._todo[0]:
            self._todo.pop(0)
            frame = self.cam.read(t, self.run.data) if self.render else None
            truth = self.cam.last_truth if self.render else self.cam.truth(t, self.run.data)
            self.seen.append((t, truth, frame, tuple(self.run.vehicle.q[:7])))


def hover_over(actor, spy, people=()):
    return fa.Mission(fa.drone("dji-mavic-2-pro"), fa.pilots.Hover(altitude=15.0),
                      world=fa.World.scene(people=people, size=(120.0, 120.0)), actors=[actor],
                      components=[spy], until=40.0)


def test_every_frame_truth_has_the_actor_where_it_is():
    bob = fa.actors.Person([(-5.0, 2.0), (5.0, 2.0)], speed=0.5, start_s=12.0, name="bob")
    spy = Spy(np.arange(14.0, 32.0, 2.0))
    hover_over(bob, spy, people=[(-20.0, -20.0)]).run()
    assert len(spy.seen) == 9
    cam = spy.cam
    lens = (cam.width, cam.height, cam.fov_deg, cam.pitch_deg)
    for t, truth, _, nav in spy.seen:
        objs = truth.objects
        assert 1 in objs.ids                      # world person 0, then the actor: id 1
        x0, y0, x1, y1 = objs.boxes[list(objs.ids).index(1)]
        gx, gy = ground_point((x0 + x1) / 2, (y0 + y1) / 2, nav, lens, 0.85)
        assert math.dist((gx, gy), bob.at(t)[:2]) < 0.3


def test_a_rendered_frame_shows_the_actor_in_its_truth_box():
    car = fa.actors.Car([(-12.0, 0.0), (12.0, 0.0)], speed=1.0, start_s=10.0)
    spy = Spy([18.0, 26.0], render=True)
    hover_over(car, spy).run()
    paint = np.array([0.1, 0.3, 0.8]) * 255
    for _t, truth, frame, _ in spy.seen:
        x0, y0, x1, y1 = truth.objects.boxes[0].astype(int)
        inside = frame[y0:y1, x0:x1].reshape(-1, 3).astype(float)
        blue = np.linalg.norm(inside - paint, axis=1) < 90
        assert blue.mean() > 0.2                        # the body's paint fills the box
        outside = np.ones(frame.shape[:2], bool)
        outside[max(y0 - 3, 0):y1 + 3, max(x0 - 3, 0):x1 + 3] = False
        far = frame[outside].astype(float)
        assert (np.linalg.norm(far - paint, axis=1) < 90).mean() < 0.01
