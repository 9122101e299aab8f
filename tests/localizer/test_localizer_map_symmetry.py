"""A symmetric map keeps a converged AMCL pose unearned (the 40 m hallway case)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from symloc.errors import ConfigurationError
from symloc.localizer import Hypothesis, Localizer, Status, SymmetryVerdict, TrackerResult
from symloc.localizer.map_symmetry import MapSymmetry, map_symmetries
from symloc.odometry import OdometryReading
from symloc.sim.rasterize import world_to_grid
from symloc.sim.rooms import build_room, hallway, l_shaped_room
from symloc.symmetry.order import SymmetryOrder


def test_map_symmetries_of_a_hallway_and_an_l_shape():
    hall = world_to_grid(hallway(20.0, 2.0).world, 0.05)
    found = map_symmetries(hall)
    assert [m.order for m in found] == [2]
    assert np.allclose(found[0].centre, [0.0, 0.0], atol=0.05)
    ell = world_to_grid(l_shaped_room(4.0).world, 0.05)
    assert map_symmetries(ell, min_overlap=0.9) == []
    # an L is three quarters of a square: a near symmetry of order 4, not an exact one
    assert [(m.order, m.overlap < 0.75) for m in map_symmetries(ell)] == [(4, True)]
    square = world_to_grid(build_room("square", 2.0, lab=False).world, 0.05)
    assert {m.order for m in map_symmetries(square, min_overlap=0.9)} == {2, 4}


def test_map_symmetries_rejects_bad_settings():
    grid = world_to_grid(hallway(10.0, 2.0).world, 0.05)
    with pytest.raises(ConfigurationError, match="tolerance"):
        map_symmetries(grid, tolerance=0.0)
    with pytest.raises(ConfigurationError, match="min_overlap"):
        map_symmetries(grid, min_overlap=1.5)


class _Tracker:
    def __init__(self, result: TrackerResult) -> None:
        self.result = result

    def initialize_global(self) -> None:
        pass

    def initialize_pose(self, pose, covariance) -> None:
        pass

    def force_update(self) -> None:
        pass

    def update(self, odom, scan) -> TrackerResult:
        return self.result


class _Store:
    def candidates(self, gv_distance, order):
        return []


def _asym(scan) -> SymmetryVerdict:
    return SymmetryVerdict(
        False, SymmetryOrder.finite(1), "asymmetric", None, math.nan, reason="one end seen"
    )


@pytest.mark.parametrize("copy_fits", [True, False])
def test_converged_pose_is_earned_only_when_no_map_copy_fits(copy_fits):
    pose = np.array([15.0, 0.3, 0.2])
    cov = np.diag([0.02**2, 0.02**2, math.radians(1.0) ** 2])
    result = TrackerResult(pose, cov, (Hypothesis(pose, 1.0),), confident=True)

    def scorer(poses, scan):
        return np.array([1.0] + [0.95 if copy_fits else 0.2] * (len(poses) - 1))

    loc = Localizer(
        _Tracker(result),
        _asym,
        _Store(),
        scorer=scorer,
        map_symmetries=[MapSymmetry(np.zeros(2), 2, 1.0)],
    )
    loc.reset_global()
    ests = [loc.update(OdometryReading(np.zeros(3)), None) for _ in range(6)]
    if copy_fits:
        assert all(e.status is Status.AMBIGUOUS and e.pose is None for e in ests)
        assert ests[-1].order == SymmetryOrder.finite(2)
        mirrored = ests[-1].hypotheses[1].pose
        assert np.allclose(mirrored[:2], [-15.0, -0.3])
    else:
        assert ests[-1].status is Status.TRACKING
        assert np.allclose(ests[-1].pose, pose)
