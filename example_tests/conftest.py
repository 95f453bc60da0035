"""Shared settings of the example suite: the paper's drone and flight plan.

The paper (FlockAI, Future Internet 2021) flies a DJI Mavic 2 Pro over an
urban area with a bounding-box zig-zag pilot. Default runs are short missions
gated on ``endurance_s`` (projected flight time at the mission's mean power),
so the whole directory runs in seconds.
"""

import pytest

import pytest_flockai as fa


def zigzag():
    """A 200 m x 120 m survey at 30 m, 25 m between legs, 8 m/s (about 3.5 min)."""
    return fa.pilots.ZigZag(area=((0, 0), (200, 120)), altitude=30, spacing=25, speed=8)


@pytest.fixture
def pilot():
    return zigzag()
