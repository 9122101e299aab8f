"""A claim withheld for the length of its covariance alone is published as an axis estimate."""

from __future__ import annotations

import math

import numpy as np

from symloc.grid.fields import surface_distance_field
from symloc.localizer import Localizer, Status
from symloc.localizer.adapters import AmclTracker, GridScorer, ReportJudge
from symloc.localizer.claim import ClaimConfig, ClaimGate
from symloc.localizer.map_symmetry import map_symmetries
from symloc.localizer.withheld_axis import across_outside_probability, withheld_axis
from symloc.mcl import Amcl, AmclParams
from symloc.sim.lidar import RPLIDAR_A2, simulate_scan
from symloc.sim.rasterize import world_to_grid
from symloc.sim.robot import DiffDriveRobot, OdometryNoise, RobotConfig
from symloc.sim.rooms import hallway
from symloc.symmetry import SymmetryConfig, judge_symmetry

ALPHAS = (0.05, 0.05, 0.05, 0.05)
COV = np.diag([0.02**2, 0.02**2, math.radians(1.0) ** 2])
#: a lidar whose scale is known to 0.75 %: 5 m from the map's middle, 3.75 cm std along it
SCALED = ClaimConfig(map_std_xy=0.01, map_scale_std=0.0075)


def _hallway():
    room = hallway(12.0, 3.0)  # both ends in range: the scan pins the pose everywhere
    grid = world_to_grid(room.world, 0.05, free_seeds=room.center[None, :])
    centre = np.asarray(room.center, dtype=np.float64)
    gate = ClaimGate(surface_distance_field(grid), ALPHAS, SCALED, scale_centre=centre)
    return room, grid, centre, gate


def test_a_pose_withheld_for_the_maps_scale_is_an_axis_along_the_radius() -> None:
    room, _, centre, gate = _hallway()
    far = np.array([centre[0] + 5.0, centre[1] + 0.1, 0.05])
    claim = gate.confirm(far, COV, simulate_scan(room.world, far, RPLIDAR_A2, 0))
    assert not claim.ok
    est = withheld_axis(gate, claim, earned=True)
    assert est is not None
    assert est.status is Status.AXIS
    assert est.axis is not None
    along = est.axis.ends[1] - est.axis.ends[0]
    assert abs(along[0]) > 10 * abs(along[1])  # along the hallway, away from its middle
    assert 0.1 < float(np.hypot(*along)) < 0.3  # +-2 std of 3.75 cm and the rest
    assert abs(math.remainder(est.axis.pose[2] - far[2], 2 * math.pi)) < math.radians(0.5)
    assert float(np.hypot(*(est.axis.pose[:2] - far[:2]))) < 0.05
    # not earned (its copies never checked): nothing
    assert withheld_axis(gate, claim, earned=False) is None
    # a pose the gate claims, or one whose scan fits only partly, is no axis
    near = np.array([centre[0] + 1.0, centre[1] + 0.1, 0.05])
    assert (
        withheld_axis(
            gate, gate.confirm(near, COV, simulate_scan(room.world, near, RPLIDAR_A2, 0)), True
        )
        is None
    )
    scan = simulate_scan(room.world, far, RPLIDAR_A2, 0)
    r = scan.ranges.copy()
    r[: int(0.5 * r.size)] = 0.5  # a person right in front of the lidar
    partly = gate.confirm(far, COV, scan.with_ranges(r))
    assert withheld_axis(gate, partly, True) is None


def test_the_position_across_is_held_to_the_gates_chance_in_one_direction() -> None:
    """The across std may reach 2.79 cm for a 10 cm tolerance at four sigmas (the gate's
    chance, 3.4e-4, in one direction), not the 2.5 cm of the 2-D pose's circular bound; a
    heading std past the gate's bound reports nothing."""
    import dataclasses

    room, _, centre, gate = _hallway()
    far = np.array([centre[0] + 5.0, centre[1] + 0.1, 0.05])
    claim = gate.confirm(far, COV, simulate_scan(room.world, far, RPLIDAR_A2, 0))
    cfg = gate.config
    assert across_outside_probability(0.0275, 0.1) < cfg.max_outside_probability
    assert across_outside_probability(0.0285, 0.1) > cfg.max_outside_probability
    assert across_outside_probability(0.0, 0.1) == 0.0

    def with_std(across: float, heading_deg: float = 0.3):  # type: ignore[no-untyped-def]
        cov = np.diag([0.06**2, across**2, math.radians(heading_deg) ** 2])
        return dataclasses.replace(claim, covariance=cov)

    assert cfg.max_std_xy < 0.027  # past the circular bound, within the 1-D one
    est = withheld_axis(gate, with_std(0.027), True)
    assert est is not None
    assert est.status is Status.AXIS
    assert withheld_axis(gate, with_std(0.029), True) is None
    assert withheld_axis(gate, with_std(0.02, heading_deg=1.4), True) is None


def _localizer():
    room, grid, centre, _ = _hallway()
    amcl = Amcl(grid, AmclParams(alpha1=0.05, alpha2=0.05, alpha3=0.05, alpha4=0.05), 3)
    gate = ClaimGate(surface_distance_field(grid), ALPHAS, SCALED, scale_centre=centre)
    loc = Localizer(
        AmclTracker(amcl),
        ReportJudge(judge_symmetry, config=SymmetryConfig.from_lidar(RPLIDAR_A2)),
        None,  # type: ignore[arg-type]
        scorer=GridScorer(grid),
        claim_gate=gate,
        map_symmetries=map_symmetries(grid),
    )
    return room, centre, loc


def _tracking_near_the_middle():  # type: ignore[no-untyped-def]
    """The hallway's localizer, and a robot 0.5 m from its middle whose pose the operator gave."""
    room, centre, loc = _localizer()
    robot = DiffDriveRobot(
        np.array([centre[0] + 0.5, centre[1], 0.0]),
        RobotConfig(noise=OdometryNoise(0.01, 0.01, 0.01, 0.01)),
        5,
    )
    loc.set_pose(robot.pose.copy(), COV)
    return room, centre, loc, robot


def test_tracking_far_from_the_middle_reports_the_heading_and_an_operator_pose_does_not() -> None:
    """From a confirmed pose near the hallway's middle the robot drives 4.5 m along it: claims
    are withheld for the map's scale, and the heading and the position across the hallway are
    reported (status axis), right. An operator's pose given out there was never confirmed:
    its half-turned copy was never ruled out, so nothing is reported."""
    room, centre, loc, robot = _tracking_near_the_middle()
    rng = np.random.default_rng(13)
    seen = []
    for _ in range(100):
        est = loc.update(robot.odometry(), simulate_scan(room.world, robot.pose, RPLIDAR_A2, rng))
        seen.append(est.status)
        if est.status is Status.AXIS:
            assert est.axis is not None
            assert abs(
                math.remainder(est.axis.pose[2] - robot.pose[2], 2 * math.pi)
            ) < math.radians(5)
            assert abs(est.axis.pose[1] - robot.pose[1]) < 0.1
        robot.step(0.45, 0.0, 0.1)
    assert seen[0] is Status.TRACKING
    assert seen[-1] is Status.AXIS

    room, centre, loc = _localizer()
    far = np.array([centre[0] + 5.0, centre[1], 0.0])
    loc.set_pose(far, COV)
    statuses = [
        loc.update(robot.odometry(), simulate_scan(room.world, far, RPLIDAR_A2, rng)).status
        for _ in range(10)
    ]
    assert Status.AXIS not in statuses
    assert Status.TRACKING not in statuses


def test_no_axis_from_scans_taken_while_turning_fast() -> None:
    """Withheld far from the middle, the robot turns on the spot: at 0.7 rad/s (above
    ``axis_max_turn``) nothing is reported, at 0.1 rad/s the axis is."""
    room, _, loc, robot = _tracking_near_the_middle()
    rng = np.random.default_rng(14)

    def statuses(v: float, w: float, n: int) -> list[Status]:
        out = []
        for _ in range(n):
            odom = robot.odometry()
            scan = simulate_scan(room.world, robot.pose, RPLIDAR_A2, rng, stamp=odom.stamp)
            out.append(loc.update(odom, scan).status)
            robot.step(v, w, 0.1)
        return out

    statuses(0.45, 0.0, 100)  # out to 5 m from the middle, claims withheld there
    assert Status.AXIS not in statuses(0.0, 0.7, 8)[1:]
    assert statuses(0.0, 0.1, 8)[-1] is Status.AXIS


def test_axis_max_turn_must_be_a_positive_rate() -> None:
    import pytest

    from symloc.errors import ConfigurationError
    from symloc.localizer import LocalizerConfig

    for bad in (0.0, -0.1, math.nan, math.inf):
        with pytest.raises(ConfigurationError, match="axis_max_turn"):
            LocalizerConfig(axis_max_turn=bad)
