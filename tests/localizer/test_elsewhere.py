"""Places elsewhere: followed by odometry, dropped when they stop explaining the scans."""

from __future__ import annotations

import math

import numpy as np

from symloc.geometry import wrap_angle
from symloc.localizer.elsewhere import Places, nearest_within, places_explaining
from symloc.localizer.types import Proposal


def test_places_explaining_keeps_those_at_or_above_the_need() -> None:
    p = Proposal(np.array([[0.0, 0, 0], [1.0, 0, 0], [2.0, 0, 0]]), np.array([0.9, 0.6, 0.5]), True)
    assert places_explaining(p, 0.6)[:, 0].tolist() == [0.0, 1.0]
    assert places_explaining(p, 0.95).shape == (0, 3)


def test_nearest_within_the_window_in_position_and_heading() -> None:
    poses = np.array([[3.0, 0.0, 0.0], [0.5, 0.0, 1.0], [0.5, 0.0, 0.2]])
    assert nearest_within(poses, np.zeros(3), (1.0, math.radians(45))) == 2
    assert nearest_within(poses, np.zeros(3), (0.1, math.pi)) is None


def test_followed_places_are_carried_by_odometry_and_kept_while_they_fit() -> None:
    seen = []

    def align(pose, scan):  # type: ignore[no-untyped-def]
        seen.append(np.asarray(pose).copy())
        return pose, 0.9 if pose[0] > 0 else 0.1  # the place at +x fits, the one at -x not

    places = Places(np.array([[1.0, 0.0, 0.0], [-1.0, 0.0, math.pi]]), np.zeros(3), complete=False)
    step = np.array([0.5, 0.0, 0.1])  # the odometry moved half a metre forward and turned
    after = places.followed(step, scan=None, align=align, min_fit=0.6)  # type: ignore[arg-type]
    assert after is not None
    assert after.poses.shape == (1, 3)
    # each place moved by the odometry's step in its own frame
    assert np.allclose(seen[0], [1.5, 0.0, 0.1])
    assert np.allclose(seen[1][:2], [-1.5, 0.0])
    assert math.isclose(float(wrap_angle(seen[1][2] - (math.pi + 0.1))), 0.0, abs_tol=1e-12)
    assert after.scans == 1
    assert math.isclose(after.path, 0.5)
    assert math.isclose(after.turned, 0.1)
    assert not after.moved((1.0, math.pi / 2))
    assert after.moved((0.5, math.pi / 2))
    none = after.followed(step, scan=None, align=lambda p, s: (p, 0.0), min_fit=0.6)  # type: ignore[arg-type]
    assert none is None
