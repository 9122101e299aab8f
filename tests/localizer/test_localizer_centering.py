"""Tests of the Algorithm 2 controller (pure function) and the centre filter."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from symloc.errors import ConfigurationError
from symloc.geometry import compose, inverse
from symloc.localizer.centering import CenteringConfig, CentreFilter, centering_command
from symloc.scan import LaserScan


def _scan(ranges) -> LaserScan:
    r = np.asarray(ranges, float)
    return LaserScan(-math.pi, 2 * math.pi / len(r), 0.1, 12.0, r)


def test_done_within_tolerance_and_facing():
    cmd = centering_command([0.003, 0.0], 0.001)
    assert cmd.phase == "done"
    assert cmd.v == 0.0
    assert cmd.w == 0.0


def test_turns_to_face_the_corner_middle_at_the_centre():
    cmd = centering_command([0.001, 0.0], 0.5)
    assert cmd.phase == "face"
    assert cmd.v == 0.0
    assert cmd.w > 0


def test_circle_has_no_facing_step():
    assert centering_command([0.0, 0.001], None).phase == "done"


def test_turns_on_the_spot_when_the_bearing_is_large_and_reverses_when_behind():
    cmd = centering_command([0.0, 1.0], None)
    assert cmd.phase == "turn"
    assert cmd.v == 0.0
    assert cmd.w > 0
    back = centering_command([-1.0, 0.01], None)
    assert back.phase == "drive"
    assert back.v < 0


def test_blocked_by_an_obstacle_in_the_direction_of_travel():
    ranges = np.full(360, 3.0)
    ranges[170:190] = 0.15  # an obstacle right ahead (beam 180 points along +x)
    cmd = centering_command([1.0, 0.0], None, _scan(ranges))
    assert cmd.phase == "blocked"
    assert cmd.v == 0.0
    free = centering_command([1.0, 0.0], None, _scan(np.full(360, 3.0)))
    assert free.phase == "drive"
    assert free.v > 0


def test_unknown_target_stops():
    cmd = centering_command(None, None)
    assert cmd.phase == "blocked"
    assert cmd.v == 0.0


@settings(max_examples=30, deadline=None)
@given(x=st.floats(-2, 2), y=st.floats(-2, 2), th=st.floats(-3.1, 3.1))
def test_closed_loop_with_perfect_sensing_reaches_the_centre(x, y, th):
    pose = np.array([x, y, th])
    centre = np.zeros(3)
    dt = 0.1
    for _ in range(2000):
        target = compose(inverse(pose), centre)[:2]
        facing = float(-pose[2])  # face along world +x
        cmd = centering_command(target, math.atan2(math.sin(facing), math.cos(facing)))
        if cmd.phase == "done":
            break
        pose = compose(pose, [cmd.v * dt, 0.0, cmd.w * dt])
    assert cmd.phase == "done"
    assert np.hypot(pose[0], pose[1]) <= 0.005 + 1e-9
    assert abs(math.atan2(math.sin(pose[2]), math.cos(pose[2]))) <= math.radians(1.0) + 1e-9


def test_centre_filter_carries_the_centre_along_odometry_and_smooths():
    f = CentreFilter(alpha=0.5)
    assert f.update([0, 0, 0], None) is None
    np.testing.assert_allclose(f.update([0, 0, 0], [1.0, 0.0]), [1.0, 0.0])
    # robot moved 0.5 m forward: the same centre is now 0.5 m ahead
    np.testing.assert_allclose(f.update([0.5, 0, 0], None), [0.5, 0.0])
    # a new estimate 0.1 m off is blended half-way
    np.testing.assert_allclose(f.update([0.5, 0, 0], [0.6, 0.0]), [0.55, 0.0])
    # a far estimate replaces it
    np.testing.assert_allclose(f.update([0.5, 0, 0], [3.0, 0.0]), [3.0, 0.0])
    f.reset()
    assert f.update([0, 0, 0], None) is None


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"position_tolerance": 0.0}, "position_tolerance"),
        ({"heading_gate": 2.0}, "heading_gate"),
        ({"max_linear_speed": -1.0}, "max_linear_speed"),
    ],
)
def test_config_validation(kw, match):
    with pytest.raises(ConfigurationError, match=match):
        CenteringConfig(**kw)


def test_filter_validation():
    with pytest.raises(ConfigurationError, match="alpha"):
        CentreFilter(alpha=0.0)
