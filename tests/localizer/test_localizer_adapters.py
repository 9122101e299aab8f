"""Tests of the adapters from the real parts to the localizer's Protocols."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from symloc.errors import ConfigurationError
from symloc.grid import OccupancyGrid
from symloc.localizer.adapters import (
    GlobalSearchProposer,
    GridScorer,
    ReportJudge,
    corner_middle_bearing,
    open_width,
    verdict_from,
)
from symloc.localizer.directions import directions_for
from symloc.mcl.global_search import GlobalSearch
from symloc.scan import LaserScan
from symloc.symmetry.order import SymmetryOrder


def _report(**kw):
    base = {
        "kind": "polygon",
        "symmetric": True,
        "order": SymmetryOrder.finite(4),
        "center": np.array([1.0, 0.0]),
        "corners": np.array([[2.0, -1.0], [2.0, 1.0], [0.0, 1.0], [0.0, -1.0]]),
        "gv_distance": math.sqrt(2.0),
        "reason": "ok",
    }
    base.update(kw)
    return SimpleNamespace(**base)


def test_corner_middle_bearing_picks_the_smallest_turn():
    corners = np.array([[2.0, -1.0], [2.0, 1.0], [0.0, 1.0], [0.0, -1.0]])
    assert corner_middle_bearing(corners) == pytest.approx(0.0)
    assert corner_middle_bearing(corners[:1]) is None


def test_verdict_from_polygon_has_facing_and_axis():
    v = verdict_from(_report())
    assert v.symmetric
    assert v.order == SymmetryOrder.finite(4)
    np.testing.assert_allclose(v.center, [1.0, 0.0])
    assert v.facing == pytest.approx(0.0)
    # axis: from the centre (1, 0) to the middle of corners 0 and 1, (2, 0): along +x
    assert v.axis == pytest.approx(0.0)


def test_verdict_from_circle_is_a_circle_and_has_no_facing():
    v = verdict_from(_report(kind="circle", order=SymmetryOrder.CIRCLE, corners=np.zeros((0, 2))))
    assert v.order == SymmetryOrder.CIRCLE
    assert v.facing is None
    assert v.axis is None


def test_verdict_from_nan_centre_is_not_symmetric():
    v = verdict_from(_report(center=np.array([np.nan, np.nan])))
    assert not v.symmetric
    assert v.center is None


def test_report_judge_counts_a_raising_judgement_as_unknown():
    def broken(scan, **kw):
        raise IndexError("index 802 is out of bounds")

    judge = ReportJudge(broken)
    v = judge(None)
    assert not v.symmetric
    assert v.kind == "unknown"
    assert judge.errors == 1
    assert "IndexError" in v.reason


def _box_grid() -> OccupancyGrid:
    data = np.zeros((60, 60), dtype=np.int8)
    data[10, 10:50] = 100
    data[49, 10:50] = 100
    data[10:50, 10] = 100
    data[10:50, 49] = 100
    data[15:20, 40:45] = 100  # a box that breaks the symmetry
    return OccupancyGrid(data, 0.05, np.zeros(3))


def _scan_from(grid: OccupancyGrid, pose) -> LaserScan:
    """Exact scan by marching along the beams on the grid."""
    angles = np.linspace(-math.pi, math.pi, 180, endpoint=False)
    r = np.linspace(0.05, 3.0, 600)
    ranges = np.full(angles.size, np.inf)
    for i, a in enumerate(angles):
        pts = np.column_stack(
            [pose[0] + r * math.cos(pose[2] + a), pose[1] + r * math.sin(pose[2] + a)]
        )
        cells = grid.world_to_cell(pts)
        ok = grid.in_bounds(cells)
        hit = np.zeros(len(r), bool)
        hit[ok] = grid.data[cells[ok, 0], cells[ok, 1]] >= 65
        if hit.any():
            ranges[i] = r[np.argmax(hit)]
    return LaserScan(-math.pi, 2 * math.pi / 180, 0.05, 3.0, ranges)


def test_grid_scorer_prefers_the_true_pose_over_a_rotated_copy():
    grid = _box_grid()
    pose = np.array([1.2, 1.0, 0.3])
    scan = _scan_from(grid, pose)
    centre = np.array([1.5, 1.5])
    rot = np.array([2 * centre[0] - pose[0], 2 * centre[1] - pose[1], pose[2] + math.pi])
    scores = GridScorer(grid)(np.array([pose, rot]), scan)
    assert scores[0] > 0.8
    assert scores[1] < scores[0]


def test_grid_scorer_validates_sigma():
    with pytest.raises(ConfigurationError, match="sigma"):
        GridScorer(_box_grid(), sigma=0.0)


def test_directions_for():
    assert directions_for("polygon", SymmetryOrder.finite(3)) == 3
    assert directions_for("polygon", SymmetryOrder.finite(6)) == 6
    assert directions_for("rectangle", SymmetryOrder.finite(2)) == 4
    assert directions_for("circle", SymmetryOrder.CIRCLE) == 8
    with pytest.raises(ConfigurationError, match="order"):
        directions_for("polygon", SymmetryOrder.finite(1))


def test_verdict_in_the_robot_frame_with_a_laser_pose():
    """A laser 0.2 m ahead looking back: the centre it reports is turned into the base frame,
    and the facing bearing and axis are the robot's."""
    laser = np.array([0.2, 0.0, math.pi])
    v = verdict_from(_report(), laser)
    np.testing.assert_allclose(v.center, [0.2 - 1.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(v.corners[0], [0.2 - 2.0, 1.0], atol=1e-12)
    # in the base frame the corner middles lie at x = -1.8 and 0.2 (ahead: bearing 0)
    assert v.facing == pytest.approx(0.0, abs=1e-12)
    assert verdict_from(_report(), [0.0, 0.0, 0.0]).center == pytest.approx([1.0, 0.0])
    with pytest.raises(ConfigurationError, match="laser_pose"):
        verdict_from(_report(), [0.0, 0.0])


def test_grid_scorer_scores_robot_poses_with_the_laser_offset():
    grid = _box_grid()
    laser = np.array([0.2, 0.0, math.pi])
    robot = np.array([1.2, 1.0, 0.3])
    at = np.array([1.2 + 0.2 * math.cos(0.3), 1.0 + 0.2 * math.sin(0.3), 0.3 + math.pi])
    scan = _scan_from(grid, at)  # what the laser on the robot sees
    with_mount = GridScorer(grid, laser_pose=laser)(np.array([robot]), scan)[0]
    without = GridScorer(grid)(np.array([robot]), scan)[0]
    assert with_mount > 0.8
    assert without < 0.5 * with_mount
    assert with_mount == pytest.approx(GridScorer(grid)(np.array([at]), scan)[0])


def _half_corridor(closed: bool) -> OccupancyGrid:
    """A corridor 3.5 m x 1.5 m in unknown space, its far end unmapped unless ``closed``
    (the map of a mapping trip that left the rest of the corridor out)."""
    data = np.full((40, 90), -1, dtype=np.int8)
    data[5:35, 5:80] = 0
    data[5, 5:80] = 100
    data[34, 5:80] = 100
    data[5:35, 5] = 100
    if closed:
        data[5:35, 79] = 100
    data[6:9, 6:9] = 100  # a box in the corner: one pose explains the scan
    return OccupancyGrid(data, 0.05, np.zeros(3))


def test_open_width_measures_where_free_space_meets_unmapped_space():
    assert open_width(_half_corridor(closed=True)) == 0.0
    assert open_width(_half_corridor(closed=False)) == pytest.approx(1.4, abs=0.15)


def test_global_search_proposer_is_never_complete_on_an_open_map():
    """Half a corridor mapped: the one pose the map has may be the 180-degree copy of where
    the robot stands in the unmapped half, so the laser alone must not decide (the decide
    path's "one survivor" needs a complete search)."""
    pose = np.array([0.8, 1.0, 0.2])
    closed = _half_corridor(closed=True)
    found = GlobalSearchProposer(GlobalSearch(closed)).propose(_scan_from(closed, pose))
    assert found.complete, found.reason
    assert len(found.poses) >= 1
    open_map = _half_corridor(closed=False)
    found = GlobalSearchProposer(GlobalSearch(open_map)).propose(_scan_from(open_map, pose))
    assert not found.complete
    assert "the map is open" in found.reason
