"""Odometry calibration error, actuation error and wheel slip of the simulated robot."""

from __future__ import annotations

import math

import numpy as np
import pytest

from symloc.errors import ConfigurationError
from symloc.geometry import angle_diff, relative
from symloc.sim.robot import (
    DiffDriveRobot,
    OdometryNoise,
    RobotConfig,
    WheelSlip,
    integrate_velocity,
)

NO_NOISE = OdometryNoise(0.0, 0.0, 0.0, 0.0)


def _drive(robot: DiffDriveRobot, v: float, w: float, steps: int, dt: float = 0.1) -> float:
    """Drive and return the odometry's summed heading change [rad] (unwrapped)."""
    total = 0.0
    prev = robot.odometry().pose[2]
    for _ in range(steps):
        assert robot.step(v, w, dt)
        cur = robot.odometry().pose[2]
        total += float(angle_diff(cur, prev))
        prev = cur
    return total


def test_default_robot_moves_exactly_as_commanded() -> None:
    robot = DiffDriveRobot([0.1, 0.2, 0.3], RobotConfig(), 0)
    pose = np.array([0.1, 0.2, 0.3])
    for v, w in ((0.3, 0.0), (0.2, 0.5), (0.0, -1.0), (-0.1, 0.2)):
        robot.step(v, w, 0.1)
        pose = integrate_velocity(pose, v, w, 0.1)
        assert np.allclose(robot.pose, pose)
    assert not robot.slipping


def test_distance_scale_error() -> None:
    cfg = RobotConfig(noise=NO_NOISE, odom_scale_error=0.015)
    robot = DiffDriveRobot([0, 0, 0], cfg, 0)
    _drive(robot, 0.5, 0.0, 20)  # 1 m
    assert robot.pose[0] == pytest.approx(1.0)
    assert robot.odometry().pose[0] == pytest.approx(1.015)
    assert robot.odometry().pose[2] == pytest.approx(0.0)


def test_rotation_scale_error_and_heading_drift() -> None:
    cfg = RobotConfig(noise=NO_NOISE, odom_rotation_error=-0.01)
    robot = DiffDriveRobot([0, 0, 0], cfg, 0)
    turned = _drive(robot, 0.0, 1.0, 63)  # 6.3 rad on the spot
    assert turned == pytest.approx(0.99 * 6.3, rel=1e-9)
    assert robot.odometry().pose[:2] == pytest.approx([0.0, 0.0], abs=1e-12)
    cfg = RobotConfig(noise=NO_NOISE, odom_heading_drift=0.01)
    robot = DiffDriveRobot([0, 0, 0], cfg, 0)
    _drive(robot, 0.5, 0.0, 40)  # 2 m straight
    assert robot.pose[2] == pytest.approx(0.0)
    assert robot.odometry().pose[2] == pytest.approx(0.02, rel=1e-6)


def test_actuation_error_moves_the_robot_off_the_command_and_odometry_sees_it() -> None:
    cfg = RobotConfig(noise=NO_NOISE, actuation_noise=0.05)
    headings = []
    for seed in range(200):
        robot = DiffDriveRobot([0, 0, 0], cfg, seed)
        _drive(robot, 0.3, 0.0, 20)
        # the wheels report what they did: odometry = true motion (no slip, no calibration)
        assert np.allclose(robot.odometry().pose, robot.pose, atol=1e-9)
        headings.append(robot.pose[2])
    h = np.array(headings)
    assert abs(np.mean(h)) < 3 * np.std(h) / math.sqrt(h.size)
    # per step: dtheta = v dt (e_r - e_l) / b, sd = v dt sqrt(2) 0.05 / b; 20 steps
    expected = 0.3 * 0.1 * math.sqrt(2) * 0.05 / 0.23 * math.sqrt(20)
    assert np.std(h) == pytest.approx(expected, rel=0.15)


def test_slip_when_turning_on_the_spot_loses_motion_the_wheels_report() -> None:
    slip = WheelSlip(rate=2.0, duration=0.4, fraction_min=0.1, fraction_max=0.3)
    cfg = RobotConfig(noise=NO_NOISE, slip=slip)
    ratios = []
    slipped_steps = 0
    for seed in range(20):
        robot = DiffDriveRobot([0, 0, 0], cfg, seed)
        odo = true = 0.0
        for _ in range(50):
            before = robot.pose[2]
            o0 = robot.odometry().pose[2]
            assert robot.step(0.0, 1.0, 0.1)
            true += float(angle_diff(robot.pose[2], before))
            odo += float(angle_diff(robot.odometry().pose[2], o0))
            slipped_steps += robot.slipping
        ratios.append(true / odo)
    r = np.array(ratios)
    assert np.all(r <= 1.0 + 1e-12)
    assert np.all(r >= 0.7 - 1e-12)
    assert np.mean(r) < 0.97
    assert slipped_steps > 0
    # driving straight at a constant speed never slips (no trigger)
    robot = DiffDriveRobot([0, 0, 0], cfg, 0)
    robot.step(0.05, 0.0, 0.1)  # gentle start below the acceleration threshold
    for _ in range(50):
        robot.step(0.05, 0.0, 0.1)
        assert not robot.slipping
    assert np.allclose(robot.odometry().pose, robot.pose)


def test_slip_on_hard_acceleration() -> None:
    slip = WheelSlip(rate=50.0, duration=0.05, fraction_min=0.2, fraction_max=0.2)
    robot = DiffDriveRobot([0, 0, 0], RobotConfig(noise=NO_NOISE, slip=slip), 1)
    robot.step(0.6, 0.0, 0.1)  # 0 -> 0.6 m/s in 0.1 s: 6 m/s^2
    assert robot.slipping
    assert robot.pose[0] == pytest.approx(0.8 * 0.06)
    assert robot.odometry().pose[0] == pytest.approx(0.06)


def test_zero_mean_noise_stays_on_top_of_the_calibration_error() -> None:
    cfg = RobotConfig(noise=OdometryNoise(0.0016, 0.0001, 0.0004, 0.0001), odom_scale_error=0.02)
    ends = []
    for seed in range(300):
        robot = DiffDriveRobot([0, 0, 0], cfg, seed)
        _drive(robot, 0.5, 0.0, 10)
        ends.append(relative(robot.pose, robot.odometry().pose)[0])
    e = np.array(ends)
    assert np.mean(e) == pytest.approx(0.5 * 0.02, abs=3 * np.std(e) / math.sqrt(e.size))
    assert np.std(e) > 0.002


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"odom_scale_error": 0.6}, r"RobotConfig\.odom_scale_error"),
        ({"odom_rotation_error": math.nan}, r"RobotConfig\.odom_rotation_error"),
        ({"actuation_noise": 0.5}, r"RobotConfig\.actuation_noise"),
        ({"wheel_base": 0.0}, r"RobotConfig\.wheel_base"),
        ({"slip": "none"}, r"RobotConfig\.slip"),
    ],
)
def test_bad_robot_config_raises(kwargs: dict, match: str) -> None:
    with pytest.raises(ConfigurationError, match=match):
        RobotConfig(**kwargs)


def test_bad_slip_raises() -> None:
    with pytest.raises(ConfigurationError, match="fraction_min, fraction_max"):
        WheelSlip(fraction_min=0.5, fraction_max=0.2)
    with pytest.raises(ConfigurationError, match=r"WheelSlip\.duration"):
        WheelSlip(duration=0.0)
    with pytest.raises(ConfigurationError, match=r"WheelSlip\.rate"):
        WheelSlip(rate=-1.0)
