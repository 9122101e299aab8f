"""Degenerate scans: a long featureless corridor, where scans cannot fix the position along it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from symloc.geometry import relative
from symloc.sim.lidar import PAPER_15M, simulate_scan
from symloc.sim.odometry_noise import regime_odometry
from symloc.sim.rooms import hallway
from symloc.slam import analyse_match, fuse, run_slam
from symloc.slam.degeneracy import UNCONSTRAINED_SIGMA


def _corridor_run(regime: str, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Drive 20 m along the middle of a 60 m x 2 m corridor (ends beyond the 15 m lidar)."""
    room = hallway(60.0, 2.0, textured=False)
    rng = np.random.default_rng(seed)
    x = np.arange(-10.0, 10.0 + 1e-9, 0.4)
    truth = np.column_stack([x, 0.05 * np.sin(x / 3.0), np.zeros_like(x)])
    scans = [simulate_scan(room.world, p, PAPER_15M, rng) for p in truth]
    odom = regime_odometry(truth, regime, rng)
    res = run_slam(scans, odom, progress=False)
    return truth, odom, res.poses


@pytest.mark.parametrize(("regime", "seed"), [("realistic", 0), ("heavy", 1)])
def test_corridor_position_drifts_only_with_odometry(regime: str, seed: int) -> None:
    truth, odom, slam = _corridor_run(regime, seed)
    # how far the odometry's distance driven is off so far (its drift along the corridor)
    step = np.hypot(*np.diff(odom[:, :2], axis=0).T) - np.hypot(*np.diff(truth[:, :2], axis=0).T)
    drift = np.maximum.accumulate(np.abs(np.concatenate([[0.0], np.cumsum(step)])))
    along_slam = np.abs(slam[:, 0] - truth[:, 0])
    # the corridor gives no information along x: SLAM may not slide faster than odometry
    assert np.all(along_slam <= drift + 0.1)
    # across the corridor and in heading the scans do constrain it
    assert np.max(np.abs(slam[:, 1] - truth[:, 1])) < 0.1
    assert np.max(np.abs(slam[:, 2] - truth[:, 2])) < math.radians(3.0)


def test_analyse_match_finds_the_corridor_axis_and_fuse_keeps_the_prediction_there() -> None:
    # points on two long walls y = +-1: the curvature constrains y and theta, not x
    xs = np.linspace(-8, 8, 200)
    pts = np.concatenate(
        [np.column_stack([xs, np.ones_like(xs)]), np.column_stack([xs, -np.ones_like(xs)])]
    )
    info = np.zeros((3, 3))
    g = np.column_stack([np.zeros(400), np.sign(pts[:, 1]), pts[:, 0] * np.sign(pts[:, 1])])
    info = g.T @ g / 400  # gradients normal to the walls only
    mc = analyse_match(info, pts, 0.02)
    assert mc.n_degenerate == 1
    assert math.sqrt(mc.covariance[0, 0]) > 0.5 * UNCONSTRAINED_SIGMA
    assert math.sqrt(mc.covariance[1, 1]) < 0.1
    pred = np.array([1.0, 0.1, 0.02])
    match = np.array([3.0, 0.0, 0.0])
    fused, _ = fuse(pred, np.diag([0.04, 0.04, 0.01]), match, mc.covariance)
    assert fused[0] == pytest.approx(1.0, abs=1e-3)  # along the axis: the prediction
    assert abs(fused[1]) < 0.02  # across: the match
    full = analyse_match(np.eye(3), pts, 0.02)
    assert full.n_degenerate == 0
    assert not full.degenerate
    assert relative(np.zeros(3), fused).shape == (3,)
