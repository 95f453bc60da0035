"""Per-object ground truth: planted objects, known camera poses,
every truth box checked against an independent projection of the object's
geometry and against the rendered pixels; occlusion by buildings and by
other objects; the COCO export."""

import math

import numpy as np
import pytest
from pycocotools.coco import COCO

import pytest_flockai as fa
from pytest_flockai.sensors.views import render_views
from pytest_flockai.world.figures import CAR
from pytest_flockai.world.objects import HEAD_RADIUS, PERSON_HEIGHT, PERSON_RADIUS
from pytest_flockai.world.truth import CLASSES, gimbal_pose

W, H, FOV = 320, 240, 60.0
F = 0.5 * H / math.tan(math.radians(FOV) / 2)


def _pixel(p, cam_pos, yaw):
    """The pinhole projection written out for a camera looking straight down
    (independent of the product's project()): image x along the drone's right,
    image up along its nose (yaw)."""
    d = np.asarray(p, float) - cam_pos
    fwd = (math.cos(yaw), math.sin(yaw))
    right = (math.sin(yaw), -math.cos(yaw))
    depth = -d[2]
    x_cam = d[0] * right[0] + d[1] * right[1]
    y_cam = d[0] * fwd[0] + d[1] * fwd[1]
    return W / 2 + F * x_cam / depth, H / 2 - F * y_cam / depth


def _person_points(x, y):
    pts = []
    top = PERSON_HEIGHT - 2 * HEAD_RADIUS - 0.02
    for a in 2 * np.pi * (np.arange(8) + 0.5) / 8:
        for z in (0.0, top):
            pts.append((x + PERSON_RADIUS * math.cos(a), y + PERSON_RADIUS * math.sin(a), z))
    zc = PERSON_HEIGHT - HEAD_RADIUS
    pts += [(x, y, zc - HEAD_RADIUS), (x, y, zc + HEAD_RADIUS)]
    for k in range(1, 4):
        th = np.pi * k / 4 - np.pi / 2
        for i in range(8):
            a = 2 * np.pi * i / 8
            pts.append((x + HEAD_RADIUS * math.cos(th) * math.cos(a),
                        y + HEAD_RADIUS * math.cos(th) * math.sin(a), zc + HEAD_RADIUS * math.sin(th)))
    return pts


def _figure_points(world, i):
    """The vertices of person i as drawn (its articulated meshes), at its feet."""
    return np.vstack([v for v, _ in world.figure_meshes()[i].values()]) + world.people[i]


def _car_points(x, y, yaw):
    c, s = math.cos(yaw), math.sin(yaw)
    v = np.vstack([m[0] for m in CAR.values()])
    return np.column_stack([x + c * v[:, 0] - s * v[:, 1], y + s * v[:, 0] + c * v[:, 1], v[:, 2]])


def _expected_box(points, cam_pos, yaw):
    uv = np.array([_pixel(p, cam_pos, yaw) for p in points])
    lo, hi = uv.min(axis=0), uv.max(axis=0)
    return np.array([max(lo[0], 0), max(lo[1], 0), min(hi[0], W), min(hi[1], H)])


@pytest.fixture(scope="module")
def planted():
    people = [(0.0, 0.0), (3.0, -2.0), (-4.0, 3.0)]
    cars = [(6.0, 4.0, 0.3)]
    world = fa.World.scene(people=people, vehicles=cars, size=(60.0, 60.0), figures="articulated")
    cam, yaw = np.array([0.5, 0.5, 20.0]), 0.4
    (frame, truth), = render_views(world, [(*cam, yaw)])
    return world, people, cars, cam, yaw, frame, truth


def test_every_truth_box_is_the_projection_of_its_object_to_the_pixel(planted):
    world, people, cars, cam, yaw, _, truth = planted
    o = truth.objects
    assert sorted(o.ids.tolist()) == [0, 1, 2, 3]
    for j, oid in enumerate(o.ids):
        pts = _figure_points(world, oid) if oid < 3 else _car_points(*cars[oid - 3])
        np.testing.assert_allclose(o.boxes[j], _expected_box(pts, cam, yaw), atol=1e-6)
        assert CLASSES[o.cls[j]] == ("person" if oid < 3 else "vehicle")
    assert (o.visible == 1.0).all()
    centre = np.array([0.0, 0.0, PERSON_HEIGHT / 2])
    j0 = int(np.flatnonzero(o.ids == 0)[0])
    assert o.distance_m[j0] == pytest.approx(np.linalg.norm(centre - cam))
    assert o.gsd_m[j0] == pytest.approx((cam[2] - centre[2]) / F)


def test_a_simple_figure_box_is_the_projection_of_its_prism_and_head():
    """figures="simple" keeps the first release's figure: an octagonal prism and a head."""
    world = fa.World.scene(people=[(1.0, -2.0)], size=(60.0, 60.0), figures="simple")
    cam, yaw = np.array([0.5, 0.5, 20.0]), 0.4
    (_, truth), = render_views(world, [(*cam, yaw)])
    np.testing.assert_allclose(truth.objects.boxes[0],
                               _expected_box(_person_points(1.0, -2.0), cam, yaw), atol=1e-6)


def test_the_rendered_pixels_of_each_object_fill_its_box(planted):
    """On the rendered frame, the object's colour lies inside its box and reaches
    every edge within a pixel (the box is tight)."""
    _, _, _, _, _, frame, truth = planted
    ground = fa.World.scene(size=(60.0, 60.0))
    cam = planted[3]
    (empty, _), = render_views(ground, [(*cam, planted[4])])
    diff = np.abs(frame.astype(int) - empty.astype(int)).sum(axis=2) > 40
    o = truth.objects
    for x0, y0, x1, y1 in o.boxes:
        inside = diff[int(y0):int(math.ceil(y1)), int(x0):int(math.ceil(x1))]
        assert inside.any()
        rows, cols = np.nonzero(inside)
        assert rows.min() <= 1 and cols.min() <= 1
        assert rows.max() >= inside.shape[0] - 2 and cols.max() >= inside.shape[1] - 2
    mask = np.zeros_like(diff)
    for x0, y0, x1, y1 in o.boxes:
        mask[max(0, int(y0) - 1):int(math.ceil(y1)) + 1, max(0, int(x0) - 1):int(math.ceil(x1)) + 1] = True
    assert not (diff & ~mask).any()                  # nothing drawn outside the boxes


def test_occlusion_by_buildings_vehicles_and_the_image_border():
    building = (10.0, 0.0, 2.0, 5.0, 15.0)            # a 15 m block east of the camera
    people = [(14.0, 0.0),                            # right behind the building, seen from (0, 0, 20)
              (8.0, 20.0),                            # in the open
              (-3.0, 0.0)]                            # under the car
    cars = [(-3.0, 0.0, 0.0)]
    world = fa.World.scene(people=people, vehicles=cars, buildings=[building], size=(80.0, 80.0))
    cam = (0.0, 0.0, 20.0)
    pos, mat = gimbal_pose(cam, 0.0, -60.0)          # looking east and down: behind = hidden
    truth = fa.sensors.Camera().lens.truth(0.0, world.truth_points(), pos, mat, world.occluders,
                                           world.objects)
    vis = dict(zip(truth.objects.ids.tolist(), truth.objects.visible.tolist()))
    assert vis.get(0, 0.0) == 0.0                     # behind the building
    # the person under the car: hidden by it from above
    (_, t2), = render_views(world, [(-3.0, 0.0, 25.0, 0.0)])
    v2 = dict(zip(t2.objects.ids.tolist(), t2.objects.visible.tolist()))
    assert v2[2] < 0.3 and v2[3] > 0.9                # the person (id 2) under the car (id 3)
    # a person cut by the image border: clipped box, partly visible
    edge = fa.World.scene(people=[(0.0, 0.0)], size=(40.0, 40.0))
    # 14.8 m to the side from 20 m up: the feet (depth 20 m) project inside the image
    # (u = 160 + F * 14.8 / 20 = 314), the head (depth 18.3 m) outside (u = 328)
    (_, t3), = render_views(edge, [(-14.8, 0.0, 20.0, math.pi / 2)])
    o = t3.objects
    assert len(o) == 1 and 0.2 < o.visible[0] < 0.9
    assert o.boxes[0][0] == 0.0 or o.boxes[0][2] == W


def test_half_hidden_person_behind_a_building_edge():
    world = fa.World.scene(people=[(10.0, 0.0)], buildings=[(6.0, -0.8, 2.0, 0.8, 10.0)],
                           size=(40.0, 40.0))
    pos, mat = gimbal_pose((0.0, 0.0, 12.0), 0.0, -45.0)
    truth = fa.sensors.Camera().lens.truth(0.0, world.truth_points(), pos, mat, world.occluders,
                                           world.objects)
    assert 0.2 < truth.objects.visible[0] < 0.8


def test_dataset_export_writes_coco_that_pycocotools_loads(tmp_path, planted):
    world, *_ = planted
    views = render_views(world, [(0.5, 0.5, 20.0, 0.4), (3.0, 0.0, 30.0, 0.0)])
    fa.sensors.export_dataset([(float(i), f, t) for i, (f, t) in enumerate(views)], tmp_path)
    coco = COCO(str(tmp_path / "annotations.json"))
    assert [c["name"] for c in coco.loadCats(coco.getCatIds())] == list(CLASSES)
    for img_id, (_, truth) in zip(sorted(coco.getImgIds()), views):
        anns = coco.loadAnns(coco.getAnnIds(imgIds=[img_id]))
        got = sorted((a["object_id"], *a["bbox"]) for a in anns)
        o = truth.objects
        want = sorted((int(i), b[0], b[1], b[2] - b[0], b[3] - b[1]) for i, b in zip(o.ids, o.boxes))
        np.testing.assert_allclose(np.array(got), np.array(want), atol=2e-3)


def test_vehicles_are_placed_on_streets_apart_and_do_not_move_people():
    a = fa.World.urban(seed=5, size=(160.0, 160.0), people=50)
    b = fa.World.urban(seed=5, size=(160.0, 160.0), people=50, vehicles=30)
    np.testing.assert_array_equal(a.people, b.people)            # cars come from their own stream
    np.testing.assert_array_equal(a.buildings, b.buildings)
    assert len(b.vehicles) == 30 and len(b.objects) == 80
    xy = b.vehicles[:, :2]
    d = np.linalg.norm(xy[:, None] - xy[None], axis=2) + np.eye(30) * 1e9
    assert d.min() > 1.8                                          # no two cars in one place
    on_street = [any(x0 <= x <= x1 and y0 <= y <= y1 for x0, y0, x1, y1 in b.streets) for x, y in xy]
    assert all(on_street)
    with pytest.raises(fa.ConfigError, match="vehicles = -1 is not allowed"):
        fa.World.urban(vehicles=-1)
