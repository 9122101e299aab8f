"""The mapping trip's gyro-odometry and the plain-AMCL exploratory drive."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from symloc.bench.episode import RobotBody
from symloc.bench.explore import ExploreConfig, ExploreDrive
from symloc.errors import ConfigurationError
from symloc.sim.gyro import L3G4200D, GyroOdometryBody, GyroSpec, SimulatedGyro
from symloc.sim.robot import DiffDriveRobot, OdometryNoise, RobotConfig
from symloc.sim.rooms import build_room


def test_gyro_spec_rejects_bad_values():
    with pytest.raises(ConfigurationError, match="noise_density"):
        GyroSpec(noise_density=0.0, bias_std=0.0, scale_std=0.0)
    with pytest.raises(ConfigurationError, match="bias_std"):
        GyroSpec(noise_density=0.03, bias_std=-1.0, scale_std=0.0)
    with pytest.raises(ConfigurationError, match="dt"):
        SimulatedGyro(L3G4200D, np.random.default_rng(0)).measure(0.1, 0.0)


@settings(max_examples=20, deadline=None)
@given(st.integers(0, 2**31))
def test_gyro_heading_after_a_full_turn_stays_within_five_degrees(seed):
    gyro = SimulatedGyro(L3G4200D, np.random.default_rng(seed))
    dt, w = 0.1, 0.5
    steps = round(2 * math.pi / (w * dt))
    measured = sum(gyro.measure(w * dt, dt) for _ in range(steps))
    # std of the error: 0.2 % scale on 360 deg (0.72 deg), 0.06 dps bias over 12.6 s
    # (0.76 deg), 0.03 dps/sqrt(Hz) noise (0.1 deg): about 1.05 deg; 5 deg is 4.7 sigma
    assert abs(math.degrees(measured - w * dt * steps)) < 5.0


def test_gyro_odometry_heading_drifts_far_less_than_noisy_wheels():
    room = build_room("circle", 1.7, lab=True)
    errs = {}
    for use_gyro in (False, True):
        rng = np.random.default_rng(4)
        noise = OdometryNoise(0.2, 0.2, 0.2, 0.2)
        start = np.array([0.0, 0.0, 0.3])
        body = RobotBody(
            DiffDriveRobot(
                start, RobotConfig(noise=noise), rng, world=room.world, odom_origin=start
            )
        )
        b = GyroOdometryBody(body, SimulatedGyro(L3G4200D, rng)) if use_gyro else body
        for _ in range(200):
            b.drive(0.0, 0.8, 0.1)  # turn on the spot, as for the M images
        errs[use_gyro] = abs(math.remainder(b.odom.pose[2] - b.pose[2], 2 * math.pi))
    # 2.5 turns: 0.2 % scale std is 1.8 deg; the wheels (alpha 0.2) drift by tens of degrees
    assert errs[True] < math.radians(6.0)
    assert errs[True] < 0.5 * errs[False]


def test_explore_config_rejects_bad_values():
    with pytest.raises(ConfigurationError, match="spin_time"):
        ExploreConfig(spin_time=(1.0, 0.5))
    with pytest.raises(ConfigurationError, match="speed"):
        ExploreConfig(speed=0.0)


def test_explore_drive_moves_around_without_collisions():
    room = build_room("triangle", 2.0, lab=True)
    rng = np.random.default_rng(1)
    start = room.positions_inside(1, margin=0.4)[0]
    body = RobotBody(DiffDriveRobot([start[0], start[1], 0.0], rng=rng, world=room.world))
    drive = ExploreDrive(room.world.distance, rng)
    path = [body.pose]
    for _ in range(300):
        v, w = drive.command(body.pose, 0.1)
        body.drive(v, w, 0.1)
        path.append(body.pose)
    p = np.array(path)
    assert body.collisions == 0
    assert np.ptp(p[:, 0]) + np.ptp(p[:, 1]) > 1.0  # it went somewhere
    assert bool(np.all(room.contains(p[:, :2])))
