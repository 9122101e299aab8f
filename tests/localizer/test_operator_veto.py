"""The camera's veto over the operator's choice among a symmetric map's copies."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pytest
from test_localizer_claim import _rectangle_localizer

from symloc.errors import ConfigurationError
from symloc.localizer import Localizer, LocalizerConfig, RequestKind, Status
from symloc.localizer.types import Verification
from symloc.sim.lidar import RPLIDAR_A2, simulate_scan
from symloc.sim.robot import DiffDriveRobot, OdometryNoise, RobotConfig
from symloc.sim.rooms import Room, rectangle_room

COV = np.diag([0.03**2, 0.03**2, math.radians(1.0) ** 2])


@dataclass
class TruthCamera:
    """A camera and visual map that verify the hypothesis nearest the robot's true pose,
    and record what they were shown."""

    robot: DiffDriveRobot
    shown: list[np.ndarray] = field(default_factory=list)

    def keyframe_count(self) -> int:
        return 10

    def expected_counts(self, poses: np.ndarray, reach: float = 0.0) -> np.ndarray:
        return np.full(len(np.asarray(poses).reshape(-1, 3)), 10, np.int64)

    def verify(
        self,
        poses: np.ndarray,
        image: np.ndarray,
        reach: float = 0.0,
        *,
        refine: bool = False,
        round_centre: object = None,
    ) -> Verification:
        p = np.asarray(poses, float).reshape(-1, 3)
        self.shown.append(p.copy())
        d = np.hypot(*(p[:, :2] - self.robot.pose[:2]).T)
        i = int(np.argmin(d))
        return Verification(i, p[i], "scripted", {})


def _rectangle(camera_for) -> tuple[Room, DiffDriveRobot, Localizer, TruthCamera]:  # type: ignore[no-untyped-def]
    """A 4 x 2 m rectangle (the map's copies: order 2), a robot in it, and a localizer that
    knows the copies and verifies with ``camera_for(robot)``."""
    robot = DiffDriveRobot(
        np.array([*(rectangle_room(4.0, 2.0).center + np.array([-1.1, 0.4])), 0.4]),
        RobotConfig(noise=OdometryNoise(0.01, 0.01, 0.01, 0.01)),
        5,
    )
    camera = camera_for(robot)
    room, loc = _rectangle_localizer(camera)
    return room, robot, loc, camera


def _half_turned(room: Room, pose: np.ndarray) -> np.ndarray:
    c = np.asarray(room.center, float)
    return np.array([*(2.0 * c - pose[:2]), math.remainder(pose[2] + math.pi, 2 * math.pi)])


def _run(room, robot, loc, scans: int, *, images: bool = True):
    """Drive ``scans`` scans, answering image requests; (scan, status, error [m]) per scan."""
    rng = np.random.default_rng(11)
    image = None
    out = []
    for k in range(scans):
        est = loc.update(
            robot.odometry(), simulate_scan(room.world, robot.pose, RPLIDAR_A2, rng), image
        )
        image = None
        err = None if est.pose is None else float(np.hypot(*(est.pose[:2] - robot.pose[:2])))
        out.append((k, est.status, err))
        if images and est.request is not None and est.request.kind is RequestKind.CAPTURE_IMAGE:
            image = np.zeros((4, 4), np.uint8)
            continue  # the robot stands still for the picture
        robot.step(0.0, 0.3, 0.1)
    return out


def test_the_camera_vetoes_an_operator_pose_on_the_wrong_copy() -> None:
    """The operator's pose is the half-turned copy of where the robot stands (a slip of the
    hand, or a robot carried there before the laser confirmed the pose): the scan fits it
    perfectly, the camera sees the other copy, and the wrong copy is never published."""
    room, robot, loc, camera = _rectangle(TruthCamera)
    loc.set_pose(_half_turned(room, robot.pose), COV)
    out = _run(room, robot, loc, 40)
    assert out[0][1] is not Status.TRACKING  # the first confirmed scan asks the camera first
    wrong = [k for k, status, err in out if status is Status.TRACKING and err > 0.1]
    assert wrong == []
    assert camera.shown, "the camera was never asked"
    assert any("not believed" in line for line in loc.log)


def test_the_operator_pose_stands_when_the_camera_agrees_after_one_image() -> None:
    room, robot, loc, camera = _rectangle(TruthCamera)
    loc.set_pose(robot.pose.copy(), COV)
    out = _run(room, robot, loc, 20)
    first = next(k for k, status, _ in out if status is Status.TRACKING)
    assert first <= 2  # one scan asks for the image, the next claims
    assert len(camera.shown) == 1  # judged once per operator's pose
    assert all(err <= 0.1 for _, status, err in out if status is Status.TRACKING)


def test_the_operator_pose_stands_unchecked_when_no_image_comes() -> None:
    """A camera that sends nothing does not keep the operator's pose from being published:
    after ``operator_image_wait`` scans the choice stands, as without a camera."""
    room, robot, loc, camera = _rectangle(TruthCamera)
    loc.set_pose(robot.pose.copy(), COV)
    out = _run(room, robot, loc, 20, images=False)
    first = next(k for k, status, _ in out if status is Status.TRACKING)
    assert first == LocalizerConfig().operator_image_wait
    assert camera.shown == []
    assert any("stands unchecked" in line for line in loc.log)


def test_operator_image_wait_must_be_a_count() -> None:
    assert LocalizerConfig(operator_image_wait=0).operator_image_wait == 0
    for bad in (-1, 1.5, True):
        with pytest.raises(ConfigurationError, match="operator_image_wait"):
            LocalizerConfig(operator_image_wait=bad)  # type: ignore[arg-type]


@pytest.mark.parametrize(("blind", "trusted"), [(20, True), (70, False)])
def test_the_operator_pose_chooses_among_copies_only_within_its_reach(
    blind: int, trusted: bool
) -> None:
    """A lidar that returns almost nothing withholds every claim while the robot turns on the
    spot from the operator's pose (0.3 rad/s). Back within ``operator_reach`` (90 deg), the
    first claim is the operator's choice and is published at once; beyond it, it passes the
    map's copy check like any other first claim, and in a rectangle no camera, nothing,
    decides between the copies: nothing is published."""
    room, robot, loc, _ = _rectangle(lambda robot: None)
    loc.set_pose(robot.pose.copy(), COV)
    rng = np.random.default_rng(12)
    published = []
    for k in range(blind + 15):
        scan = simulate_scan(room.world, robot.pose, RPLIDAR_A2, rng)
        if k < blind:
            r = scan.ranges.copy()
            r[10:] = 0.0
            scan = scan.with_ranges(r)
        est = loc.update(robot.odometry(), scan)
        if est.status is Status.TRACKING:
            assert k >= blind
            assert float(np.hypot(*(est.pose[:2] - robot.pose[:2]))) <= 0.1
            published.append(k)
        robot.step(0.0, 0.3, 0.1)
    if trusted:
        assert published
        assert published[0] <= blind + 1
    else:
        assert published == []
        assert any("rotated copy" in line for line in loc.log)


@pytest.mark.parametrize("bad", [(-1.0, 1.0), (1.0, math.nan), (1.0,), "far"])
def test_operator_reach_must_be_metres_and_radians(bad) -> None:  # type: ignore[no-untyped-def]
    from symloc.localizer.claim import ClaimConfig

    with pytest.raises(ConfigurationError, match="operator_reach"):
        ClaimConfig(operator_reach=bad)
