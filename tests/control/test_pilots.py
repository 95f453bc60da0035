
import pytest

import pytest_flockai as fa
from pytest_flockai import ConfigError


@pytest.mark.parametrize("kwargs, field", [
    (dict(area=((0, 0), (100, 60)), altitude=30, spacing=0, speed=8), "spacing"),
    (dict(area=((0, 0), (100, 60)), altitude=30, spacing=-5, speed=8), "spacing"),
    (dict(area=((0, 0), (0, 60)), altitude=30, spacing=10, speed=8), "degenerate"),
    (dict(area=((0, 0), (100, 60)), altitude=0, spacing=10, speed=8), "altitude"),
    (dict(area=((0, 0), (100, 60)), altitude=30, spacing=10, speed=0), "speed"),
    (dict(area="box", altitude=30, spacing=10, speed=5), "area"),
])
def test_zigzag_rejects_bad_arguments(kwargs, field):
    with pytest.raises(ConfigError, match=field):
        fa.pilots.ZigZag(**kwargs)


def test_other_pilots_validate():
    with pytest.raises(ConfigError, match="altitude"):
        fa.pilots.Hover(altitude=-1)
    with pytest.raises(ConfigError, match="speed"):
        fa.pilots.Waypoints([(1, 1, 1)], speed=-2)
    with pytest.raises(ConfigError, match="empty"):
        fa.pilots.Waypoints([])
    with pytest.raises(ConfigError, match="radius"):
        fa.pilots.Orbit(center=(0, 0), radius=0)
    with pytest.raises(ConfigError, match="points\\[0\\]"):
        fa.pilots.Waypoints([(1, 1)])


def test_zigzag_covers_the_box_boustrophedon():
    z = fa.pilots.ZigZag(area=((0, 0), (100, 60)), altitude=30, spacing=20, speed=8)
    ys = sorted({p[1] for p in z.points})
    assert ys == [0, 20, 40, 60]
    # legs alternate direction along x
    assert z.points[0][0] == 0 and z.points[1][0] == 100 and z.points[2][0] == 100 and z.points[3][0] == 0
    assert all(p[2] == 30 for p in z.points)
    assert z.path_length == pytest.approx(4 * 100 + 3 * 20)


def test_zigzag_last_row_on_the_far_edge():
    z = fa.pilots.ZigZag(area=((0, 0), (50, 45)), altitude=10, spacing=20, speed=5)
    assert sorted({p[1] for p in z.points}) == [0, 20, 40, 45]
