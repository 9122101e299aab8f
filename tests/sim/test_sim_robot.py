"""Differential-drive robot, exact motion and odometry noise."""

from __future__ import annotations

import math

import numpy as np
import pytest

from symloc.errors import ConfigurationError
from symloc.geometry import relative
from symloc.odometry import OdometryIncrement
from symloc.sim.robot import (
    DiffDriveRobot,
    OdometryNoise,
    RobotConfig,
    collides,
    integrate_velocity,
    sample_motion_model_odometry,
)
from symloc.sim.rooms import build_room

NOISE = OdometryNoise(0.05, 0.02, 0.1, 0.03)


def test_sample_motion_model_statistics() -> None:
    rng = np.random.default_rng(0)
    n = 40000
    rot1, trans, rot2 = 0.3, 0.5, -0.2
    r1, tr, r2 = sample_motion_model_odometry(
        np.full(n, rot1), np.full(n, trans), np.full(n, rot2), NOISE, rng
    )
    a1, a2, a3, a4 = NOISE.alphas
    assert np.mean(r1) == pytest.approx(rot1, abs=0.003)
    assert np.mean(tr) == pytest.approx(trans, abs=0.003)
    assert np.var(r1) == pytest.approx(a1 * rot1**2 + a2 * trans**2, rel=0.05)
    assert np.var(tr) == pytest.approx(a3 * trans**2 + a4 * (rot1**2 + rot2**2), rel=0.05)
    assert np.var(r2) == pytest.approx(a1 * rot2**2 + a2 * trans**2, rel=0.05)
    assert abs(np.corrcoef(r1, r2)[0, 1]) < 0.03


def test_odometry_increment_noise_of_a_driven_robot() -> None:
    """Many robots driving the same short step: odometry increments scatter as the model says."""
    rng = np.random.default_rng(1)
    incs = []
    for _ in range(3000):
        robot = DiffDriveRobot([0, 0, 0], RobotConfig(noise=NOISE), rng)
        before = robot.odometry()
        assert robot.step(0.4, 0.5, 0.5)
        incs.append(OdometryIncrement.between(before, robot.odometry()))
    true = integrate_velocity([0, 0, 0], 0.4, 0.5, 0.5)
    trans_true = math.hypot(true[0], true[1])
    trans = np.array([i.trans for i in incs])
    a3, a4 = NOISE.alpha3, NOISE.alpha4
    r1 = math.atan2(true[1], true[0])
    r2 = true[2] - r1
    assert np.mean(trans) == pytest.approx(trans_true, rel=0.01)
    assert np.std(trans) == pytest.approx(
        math.sqrt(a3 * trans_true**2 + a4 * (r1**2 + r2**2)), rel=0.1
    )


def test_zero_noise_odometry_tracks_truth() -> None:
    robot = DiffDriveRobot([1.0, 2.0, 0.5], RobotConfig(noise=OdometryNoise(0, 0, 0, 0)), 0)
    start_odom = robot.odometry().pose
    start = robot.pose
    for v, w in [(0.3, 0.0), (0.2, 0.8), (0.0, -1.0), (-0.1, 0.2)]:
        assert robot.drive(v, w, 1.0)
    moved_true = relative(start, robot.pose)
    moved_odom = relative(start_odom, robot.odometry().pose)
    assert np.allclose(moved_true, moved_odom, atol=1e-9)
    assert robot.time == pytest.approx(4.0)


def test_exact_motion() -> None:
    p = integrate_velocity([0, 0, 0], 1.0, 0.0, 2.0)
    assert np.allclose(p, [2, 0, 0])
    full_circle = integrate_velocity([1, 1, 0.3], 0.5, 1.0, 2 * math.pi)
    assert np.allclose(full_circle, [1, 1, 0.3], atol=1e-9)
    quarter = integrate_velocity([0, 0, 0], 1.0, 1.0, math.pi / 2)
    assert np.allclose(quarter, [1, 1, math.pi / 2])


def test_odometry_drifts_with_noise_and_is_seeded() -> None:
    def run(seed: int) -> np.ndarray:
        robot = DiffDriveRobot([0, 0, 0], RobotConfig(noise=NOISE), seed)
        robot.drive(0.3, 0.2, 10.0)
        return robot.odometry().pose

    a, b, c = run(3), run(3), run(4)
    assert np.array_equal(a, b)
    assert not np.allclose(a, c)


def test_collision_stops_robot() -> None:
    room = build_room("square", 1.5 * math.sqrt(2))
    robot = DiffDriveRobot([0, 0, 0], RobotConfig(radius=0.2), 0, world=room.world)
    assert not robot.drive(0.5, 0.0, 10.0)  # would cross the board at x = 1.5
    assert 1.5 - 0.2 - 0.06 < robot.pose[0] < 1.5 - 0.2
    assert collides(room.world, [[1.4, 0.0], [0.0, 0.0]], 0.2).tolist() == [True, False]
    assert robot.collides_at([1.45, 0, 0])


def test_bad_inputs_raise() -> None:
    with pytest.raises(ConfigurationError, match="alpha2: expected a value >= 0"):
        OdometryNoise(alpha2=-0.1)
    with pytest.raises(ConfigurationError, match=r"RobotConfig\.radius"):
        RobotConfig(radius=0.0)
    robot = DiffDriveRobot([0, 0, 0], rng=0)
    with pytest.raises(ConfigurationError, match=r"v: \|v\| must be <= max_v"):
        robot.step(5.0, 0.0, 0.1)
    with pytest.raises(ConfigurationError, match="dt: expected a value > 0"):
        robot.step(0.1, 0.0, 0.0)
    with pytest.raises(ConfigurationError, match="w: expected a finite number"):
        robot.step(0.1, math.nan, 0.1)
