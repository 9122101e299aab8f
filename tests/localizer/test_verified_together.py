"""Several hypotheses verified by one image that are one pose (a round room's family)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from symloc.geometry import wrap_angle
from symloc.grid.fields import surface_distance_field
from symloc.localizer.claim import ClaimGate
from symloc.localizer.types import HypothesisVerdict, Verification
from symloc.localizer.verified_together import implied_pose, one_pose_verified
from symloc.sim.lidar import RPLIDAR_A2, simulate_scan
from symloc.sim.rasterize import world_to_grid
from symloc.sim.rooms import circular_room, regular_polygon_room

ALPHAS = (0.05, 0.05, 0.05, 0.05)
PRIOR = np.diag([0.15**2, 0.15**2, math.radians(1.0) ** 2])
TOL = math.radians(15.0)


def _family(centre: np.ndarray, truth: np.ndarray, turns: np.ndarray) -> np.ndarray:
    """``truth`` (3,) rotated about ``centre`` (2,) by each of ``turns`` (K,) [rad]."""
    rel = truth[:2] - centre
    c, s = np.cos(turns), np.sin(turns)
    xy = centre + np.stack([c * rel[0] - s * rel[1], s * rel[0] + c * rel[1]], axis=1)
    return np.column_stack([xy, wrap_angle(truth[2] + turns)])


def _answer(poses: np.ndarray, camera_heading: float, verified: set[int], inliers: dict[int, int]):
    """A store's verification of ``poses``: the ``verified`` ones measure ``camera_heading``."""
    checks = []
    for i in range(poses.shape[0]):
        if i in verified:
            off = float(wrap_angle(camera_heading - poses[i, 2]))
            checks.append(HypothesisVerdict("verified", inliers[i], off))
        elif i in inliers:
            checks.append(HypothesisVerdict("contradicted", inliers[i], math.nan))
        else:
            checks.append(HypothesisVerdict("contradicted", 0, math.nan))
    return Verification(
        None, None, "several verified", checks=tuple(checks), margin=2.0, heading_tolerance=TOL
    )


@pytest.fixture(scope="module")
def round_room():
    room = circular_room(3.0)
    grid = world_to_grid(room.world, 0.05, free_seeds=room.center[None, :])
    return room, ClaimGate(surface_distance_field(grid), ALPHAS)


def test_neighbouring_samples_of_a_round_room_are_one_pose(round_room) -> None:
    room, gate = round_room
    centre = np.asarray(room.center, dtype=np.float64)
    truth = np.array([centre[0] + 1.2, centre[1] + 0.5, 2.0])
    scan = simulate_scan(room.world, truth, RPLIDAR_A2, 0)
    # the global search's samples 22.5 deg apart; the truth lies 8 deg past sample 0
    poses = _family(centre, truth, np.radians(np.arange(16) * 22.5 - 8.0))
    answer = _answer(poses, truth[2] + math.radians(0.4), {0, 1}, {0: 80, 1: 60, 5: 12})
    one = one_pose_verified(gate, scan, poses, answer, PRIOR)
    assert one is not None
    assert one.index == 0
    assert one.members == (0, 1)
    claim = gate.confirm(one.pose, PRIOR, scan)
    assert math.hypot(*(claim.pose[:2] - truth[:2])) < 0.03
    assert abs(float(wrap_angle(claim.pose[2] - truth[2]))) < math.radians(1.0)
    assert "one pose" in one.reason


def test_a_rival_measuring_another_heading_keeps_them_apart(round_room) -> None:
    room, gate = round_room
    centre = np.asarray(room.center, dtype=np.float64)
    truth = np.array([centre[0] - 0.8, centre[1] + 1.0, -1.0])
    scan = simulate_scan(room.world, truth, RPLIDAR_A2, 1)
    poses = _family(centre, truth, np.radians(np.arange(16) * 22.5 - 5.0))
    answer = _answer(poses, truth[2], {0, 1}, {0: 50, 1: 40, 8: 30})
    # hypothesis 9 (half a turn away) has a fit measuring its own heading: a rival within 2x
    checks = list(answer.checks)
    checks[8] = HypothesisVerdict("contradicted", 30, 0.0)
    answer = Verification(None, None, "", checks=tuple(checks), margin=2.0, heading_tolerance=TOL)
    assert one_pose_verified(gate, scan, poses, answer, PRIOR) is None


def test_a_fit_measuring_the_group_heading_on_a_keyframe_no_member_sees_is_a_rival(
    round_room,
) -> None:
    room, gate = round_room
    centre = np.asarray(room.center, dtype=np.float64)
    truth = np.array([centre[0] + 1.2, centre[1] + 0.5, 2.0])
    scan = simulate_scan(room.world, truth, RPLIDAR_A2, 0)
    poses = _family(centre, truth, np.radians(np.arange(16) * 22.5 - 8.0))
    head = truth[2] + math.radians(0.4)
    answer = _answer(poses, head, {0, 1}, {0: 80, 1: 60})
    checks = list(answer.checks)
    checks[0] = HypothesisVerdict("verified", 80, checks[0].heading_offset, 10, (10, 11))
    checks[1] = HypothesisVerdict("verified", 60, checks[1].heading_offset, 11, (11, 12))
    # hypothesis 9, half a turn away, fits 50 inliers measuring the group's heading
    off = float(wrap_angle(head - poses[8, 2]))

    def with_fit(keyframe: int) -> Verification:
        c = list(checks)
        c[8] = HypothesisVerdict("contradicted", 50, off, keyframe, (40, 41))
        return Verification(None, None, "", checks=tuple(c), margin=2.0, heading_tolerance=TOL)

    # on a keyframe a member sees: evidence for the group
    assert one_pose_verified(gate, scan, poses, with_fit(12), PRIOR) is not None
    # on a keyframe elsewhere: a look-alike, a rival within 2x
    assert one_pose_verified(gate, scan, poses, with_fit(41), PRIOR) is None


def test_symmetric_copies_measuring_different_headings_are_not_merged() -> None:
    room = regular_polygon_room(4, 2.0)
    grid = world_to_grid(room.world, 0.05, free_seeds=room.center[None, :])
    gate = ClaimGate(surface_distance_field(grid), ALPHAS)
    centre = np.asarray(room.center, dtype=np.float64)
    truth = np.array([centre[0] + 0.6, centre[1] - 0.4, 0.3])
    scan = simulate_scan(room.world, truth, RPLIDAR_A2, 2)
    poses = _family(centre, truth, np.radians([0.0, 90.0, 180.0, 270.0]))
    # each copy verified against its own keyframes, each measuring its own heading
    checks = tuple(HypothesisVerdict("verified", 40, math.radians(0.5)) for _ in range(4))
    answer = Verification(None, None, "", checks=checks, margin=2.0, heading_tolerance=TOL)
    assert one_pose_verified(gate, scan, poses, answer, PRIOR) is None


def test_one_verified_or_no_margin_settings_is_not_this_case(round_room) -> None:
    room, gate = round_room
    centre = np.asarray(room.center, dtype=np.float64)
    truth = np.array([centre[0] + 1.0, centre[1], 0.0])
    scan = simulate_scan(room.world, truth, RPLIDAR_A2, 3)
    poses = _family(centre, truth, np.radians(np.arange(16) * 22.5))
    single = _answer(poses, truth[2], {0}, {0: 80})
    assert one_pose_verified(gate, scan, poses, single, PRIOR) is None
    pair = _answer(poses, truth[2], {0, 1}, {0: 80, 1: 70})
    unknown = Verification(None, None, "", checks=pair.checks)
    assert one_pose_verified(gate, scan, poses, unknown, PRIOR) is None


# ---------------------------------------------------------------- a round map's gate


@pytest.fixture(scope="module")
def round_gate(round_room):
    room, gate = round_room
    centre = np.asarray(room.center, dtype=np.float64)
    return room, ClaimGate(gate.field, ALPHAS, rotation_centre=centre)


def _fit(pose: np.ndarray, heading: float, inliers: int, keyframe: int, verified: bool):
    """A check of hypothesis ``pose`` whose fit on ``keyframe`` measures ``heading``."""
    status = "verified" if verified else "contradicted"
    off = float(wrap_angle(heading - pose[2]))
    return HypothesisVerdict(status, inliers, off, keyframe, (keyframe,))


def test_implied_pose_turns_about_a_round_maps_centre() -> None:
    centre = np.array([1.0, -2.0])
    pose = np.array([3.0, -2.0, 0.5])
    turned = implied_pose(pose, math.pi / 2, centre)
    assert np.allclose(turned, [1.0, 0.0, 0.5 + math.pi / 2])
    # no centre: the heading alone
    assert np.allclose(implied_pose(pose, 0.1), [3.0, -2.0, 0.6])


def test_on_a_round_map_fits_anywhere_measuring_one_heading_decide_one_member(round_gate) -> None:
    room, gate = round_gate
    centre = np.asarray(room.center, dtype=np.float64)
    truth = np.array([centre[0] + 1.2, centre[1] + 0.5, 2.0])
    scan = simulate_scan(room.world, truth, RPLIDAR_A2, 0)
    poses = _family(centre, truth, np.radians(np.arange(16) * 22.5 - 8.0))
    head = truth[2] + math.radians(2.0)
    checks = [HypothesisVerdict("contradicted", 0, math.nan) for _ in range(16)]
    checks[0] = _fit(poses[0], head, 80, 10, verified=True)
    # the same keyframe fitted for a sample 37 deg away (its own heading out of tolerance),
    # and a keyframe no sample expects: both measure the truth's heading, and are support
    checks[15] = _fit(poses[15], head, 80, 10, verified=False)
    checks[3] = _fit(poses[3], head - math.radians(4.0), 120, 30, verified=False)
    # a look-alike measuring another heading, under half the best verified fit
    checks[8] = _fit(poses[8], head + math.radians(60.0), 39, 50, verified=False)
    answer = Verification(None, None, "", checks=tuple(checks), margin=2.0, heading_tolerance=TOL)
    one = one_pose_verified(gate, scan, poses, answer, PRIOR)
    assert one is not None
    assert one.index == 0
    assert set(one.members) == {0, 3, 15}
    # the member of the family with the measured heading: 2 deg about the centre from the truth
    r = math.hypot(*(truth[:2] - centre))
    chord = 2.0 * r * math.sin(math.radians(1.0))
    assert math.hypot(*(one.pose[:2] - truth[:2])) == pytest.approx(chord, abs=1e-9)
    assert float(wrap_angle(one.pose[2] - head)) == pytest.approx(0.0, abs=1e-9)
    # a rival with more than half the inliers keeps it undecided
    checks[8] = _fit(poses[8], head + math.radians(60.0), 41, 50, verified=False)
    answer = Verification(None, None, "", checks=tuple(checks), margin=2.0, heading_tolerance=TOL)
    assert one_pose_verified(gate, scan, poses, answer, PRIOR) is None


def test_on_a_round_map_no_verified_fit_decides_nothing(round_gate) -> None:
    room, gate = round_gate
    centre = np.asarray(room.center, dtype=np.float64)
    truth = np.array([centre[0] - 0.8, centre[1] + 1.0, -1.0])
    scan = simulate_scan(room.world, truth, RPLIDAR_A2, 1)
    poses = _family(centre, truth, np.radians(np.arange(16) * 22.5 - 5.0))
    checks = [HypothesisVerdict("contradicted", 0, math.nan) for _ in range(16)]
    checks[2] = _fit(poses[2], truth[2], 200, 7, verified=False)
    answer = Verification(None, None, "", checks=tuple(checks), margin=2.0, heading_tolerance=TOL)
    assert one_pose_verified(gate, scan, poses, answer, PRIOR) is None
