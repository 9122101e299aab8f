"""More scans placed in a finished map: odometry carried, each aligned (slam.localize_in_map)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from symloc.errors import ConfigurationError
from symloc.geometry import compose, relative
from symloc.grid.fields import surface_distance_field
from symloc.mcl.beams import select_beams
from symloc.mcl.scan_to_map import match_scan_to_map, scan_points
from symloc.sim.lidar import RPLIDAR_A2, simulate_scan
from symloc.sim.rasterize import world_to_grid
from symloc.sim.robot import DiffDriveRobot, OdometryNoise, RobotConfig
from symloc.sim.rooms import l_shaped_room
from symloc.slam.localize_in_map import localize_in_map


def _drive(room, start, seed, steps):  # type: ignore[no-untyped-def]
    """A robot with 5 % odometry noise that turns on the spot and drives; its scans, odometry
    (the start's and one per scan) and true poses."""
    robot = DiffDriveRobot(
        np.asarray(start, float), RobotConfig(noise=OdometryNoise(0.05, 0.05, 0.05, 0.05)), seed
    )
    rng = np.random.default_rng(seed)
    odom = [np.asarray(robot.odometry().pose, float)]
    scans, truth = [], []
    for k in range(steps):
        v, w = (0.0, 0.8) if k < 80 else (0.3, 0.1)  # a full turn, then a gentle arc
        robot.step(v, w, 0.1)
        scans.append(simulate_scan(room.world, robot.pose, RPLIDAR_A2, rng))
        odom.append(np.asarray(robot.odometry().pose, float))
        truth.append(robot.pose.copy())
    return scans, np.asarray(odom), np.asarray(truth)


def test_scans_are_placed_where_the_robot_was_and_odometry_alone_drifts() -> None:
    room = l_shaped_room(8.0)
    grid = world_to_grid(room.world, 0.05, free_seeds=room.center[None, :])
    start = np.array([room.center[0], room.center[1], 0.3])
    scans, odom, truth = _drive(room, start, 4, 130)
    poses = localize_in_map(grid, scans, odom, start)
    assert poses.shape == (130, 3)
    # the raster puts every wall up to half a cell off: the map's own offset is what a scan
    # aligned from the truth finds, and the placed poses carry it, no more
    field = surface_distance_field(grid)
    beams = select_beams(scans[-1], 180)
    pts = scan_points(beams.ranges[beams.hit], beams.angles[beams.hit], (0.0, 0.0, 0.0))
    offset = match_scan_to_map(field, pts, truth[-1]).pose[:2] - truth[-1, :2]
    assert float(np.hypot(*offset)) < 0.05
    err = np.hypot(*(poses[:, :2] - truth[:, :2] - offset).T)
    head = np.abs(np.remainder(poses[:, 2] - truth[:, 2] + math.pi, 2 * math.pi) - math.pi)
    assert err.mean() < 0.02
    assert err.max() < 0.05
    assert head.max() < math.radians(2.0)
    # the odometry alone, from the same start, is off by far more by the end
    carried = np.asarray(compose(start, relative(odom[0], odom[-1])))
    assert float(np.hypot(*(carried[:2] - truth[-1, :2]))) > 3 * err[-1]
    assert abs(math.remainder(carried[2] - truth[-1, 2], 2 * math.pi)) > math.radians(1.0)


def test_a_scan_that_fits_nowhere_keeps_the_carried_pose_and_bad_input_is_named() -> None:
    room = l_shaped_room(8.0)
    grid = world_to_grid(room.world, 0.05, free_seeds=room.center[None, :])
    start = np.array([room.center[0], room.center[1], 0.3])
    scans, odom, _ = _drive(room, start, 5, 3)
    blind = [s.with_ranges(np.full(len(s), 0.4)) for s in scans]  # a box over the lidar
    poses = localize_in_map(grid, blind, odom, start)
    assert np.allclose(poses[-1], compose(start, relative(odom[0], odom[-1])), atol=1e-9)
    with pytest.raises(ConfigurationError, match="odometry"):
        localize_in_map(grid, scans, odom[1:], start)
    with pytest.raises(ConfigurationError, match="start"):
        localize_in_map(grid, scans, odom, [np.nan, 0.0, 0.0])
    with pytest.raises(ConfigurationError, match="min_fit"):
        localize_in_map(grid, scans, odom, start, min_fit=1.5)
    assert localize_in_map(grid, [], odom[:1], start).shape == (0, 3)
