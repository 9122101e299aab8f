"""Deciding from where the robot stands in a round room: the robot goes to the centre first."""

from __future__ import annotations

import math

import numpy as np

from symloc.geometry import compose, relative, wrap_angle
from symloc.localizer import RequestKind, Status
from symloc.localizer.build import build_localizer
from symloc.localizer.settings import LocalizerSettings
from symloc.localizer.types import HypothesisVerdict, Verification
from symloc.odometry import OdometryReading
from symloc.sim.lidar import RPLIDAR_A2, simulate_scan
from symloc.sim.rasterize import world_to_grid
from symloc.sim.rooms import build_room


class _Keyframes:
    """Keyframes in view of every pose; an image verifies nothing (never asked here)."""

    def keyframe_count(self) -> int:
        return 50

    def expected_counts(self, poses: np.ndarray, reach: float = 0.0) -> np.ndarray:
        return np.full(len(poses), 5, np.int64)

    def verify(
        self,
        poses: np.ndarray,
        image: np.ndarray,
        reach: float = 0.0,
        *,
        refine: bool = False,
        round_centre: object = None,
    ) -> Verification:
        return Verification(None, None, "no hypothesis verified", {})


def test_far_from_a_round_rooms_centre_deciding_here_drives_there_first() -> None:
    room = build_room("circle", 3.0, lab=False)
    grid = world_to_grid(room.world, 0.05, free_seeds=room.center[None, :])
    loc = build_localizer(grid, LocalizerSettings(seed=2), keyframes=_Keyframes())
    gate = loc.claim_gate
    assert gate is not None
    assert gate.rotation_centre is not None  # the map is round
    loc.reset_global()
    centre = np.array([*room.center, 0.0])
    truth = np.array([room.center[0] + 2.0, room.center[1] - 0.5, 2.5])
    odom = np.array([0.3, -0.2, 0.1])  # the odometry frame is not the map's
    est = loc.update(
        OdometryReading(odom.copy(), 0.0), simulate_scan(room.world, truth, RPLIDAR_A2, 0)
    )
    assert "going to its centre first" in est.reason, est.reason
    assert est.status is not Status.TRACKING
    assert est.request is not None
    assert est.request.kind is RequestKind.GO_TO
    # the target is the centre in the robot's frame, whichever rotated copy the robot is
    want = relative(truth, centre)[:2]
    assert math.hypot(*(est.request.target - want)) < 0.1
    # the robot drives there (odometry carries the target); within reach it looks around
    move = relative(truth, np.array([room.center[0] + 0.2, room.center[1], 1.0]))
    truth, odom = compose(truth, move), compose(odom, move)
    est = loc.update(
        OdometryReading(odom.copy(), 1.0), simulate_scan(room.world, truth, RPLIDAR_A2, 1)
    )
    assert est.request is not None
    assert est.request.kind is not RequestKind.GO_TO, est.reason


class _MeasuringKeyframes(_Keyframes):
    """Every hypothesis fits, measuring the true heading (``heading``, kept up to date by the
    test); the heading is never measured again (the planar-motion fits disagree)."""

    def __init__(self, heading: float) -> None:
        self.heading = heading
        self.calls: list[bool] = []

    def verify(
        self,
        poses: np.ndarray,
        image: np.ndarray,
        reach: float = 0.0,
        *,
        refine: bool = False,
        round_centre: object = None,
    ) -> Verification:
        self.calls.append(refine)
        p = np.asarray(poses, float).reshape(-1, 3)
        checks = tuple(
            HypothesisVerdict("verified", 120, float(wrap_angle(self.heading - h)), 7, (7,))
            for h in p[:, 2]
        )
        index = 0 if len(p) == 1 else None
        return Verification(
            index, p[0] if index == 0 else None, "scripted", {}, checks, 2.0, math.radians(15.0)
        )


def test_a_member_whose_heading_is_not_measured_again_is_not_awaited() -> None:
    """The coarse heading can never be claimed in a round room: another view is taken."""
    room = build_room("circle", 3.0, lab=False)
    grid = world_to_grid(room.world, 0.05, free_seeds=room.center[None, :])
    truth = np.array([room.center[0] + 0.2, room.center[1] - 0.1, 2.5])
    kf = _MeasuringKeyframes(truth[2])
    loc = build_localizer(grid, LocalizerSettings(seed=2), keyframes=kf)
    loc.reset_global()
    odom = np.zeros(3)
    image = np.zeros((4, 4), np.uint8)
    reasons = []
    for i in range(30):
        scan = simulate_scan(room.world, truth, RPLIDAR_A2, i)
        est = loc.update(OdometryReading(odom.copy(), 0.1 * i), scan, image)
        reasons.append(est.reason)
        assert est.status is not Status.TRACKING, est.reason
        if kf.calls.count(True) >= 2:
            break
        if est.request is not None and est.request.kind is RequestKind.ROTATE:
            turn = np.array([0.0, 0.0, float(est.request.angle or 0.0)])
            truth, odom = compose(truth, turn), compose(odom, turn)
            kf.heading = float(truth[2])
    # the member was decided and measured again twice, from two views, never awaited
    assert kf.calls.count(True) >= 2, reasons
    notes = list(loc.log)
    assert any("was not measured again (the planar-motion fits disagree)" in n for n in notes)
    assert not any("AMCL reseeded" in n for n in notes + reasons)
