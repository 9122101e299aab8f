"""Corridors: the axis family, the camera's heading class and the localizer's ``axis`` state."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np
import pytest
from test_localizer_decide_here import FakeProposer
from test_localizer_state_machine import FakeStore, FakeTracker, SquareJudge, _result

from symloc.bench.grading import CHI2_3DOF_95, nees
from symloc.errors import ConfigurationError
from symloc.geometry import wrap_angle
from symloc.grid import OccupancyGrid
from symloc.localizer import Estimate, Localizer, LocalizerConfig, RequestKind, Status
from symloc.localizer.axis import (
    AxisSegment,
    axis_covariance,
    axis_family,
    runs_out,
    sweep,
)
from symloc.localizer.axis_heading import vote_heading
from symloc.localizer.types import AxisPose, HypothesisVerdict, Verification
from symloc.odometry import OdometryReading

# a corridor along x from 0 to 20 m, 2 m wide; the robot 0.3 m left of its centre line
TRUTH = np.array([8.0, 0.3, 0.1])
FLIPPED = TRUTH[2] + math.pi - 2 * math.pi  # the half-turned heading, wrapped
IMAGE = np.zeros((4, 4), np.uint8)


def _line(xs, y, heading) -> np.ndarray:
    xs = np.asarray(xs, float)
    return np.column_stack([xs, np.full(xs.size, y), np.full(xs.size, heading)])


def _corridor_poses() -> np.ndarray:
    """What the laser lists in the corridor: both heading classes, interleaved, best first."""
    a = _line(np.arange(6.0, 10.01, 0.5), 0.3, TRUTH[2])
    b = _line(np.arange(6.0, 10.01, 0.5), -0.3, FLIPPED)
    return np.vstack([np.column_stack([a, b]).reshape(-1, 3)])


# --------------------------------------------------------------------------- detection


def test_a_line_of_poses_with_one_heading_is_an_axis() -> None:
    poses = _line(np.arange(2.0, 7.01, 0.5), 1.0, 0.4)
    poses[:, 1] += np.random.default_rng(0).normal(0.0, 0.01, len(poses))
    fam = axis_family(poses)
    assert fam is not None
    assert fam.count(0) == len(poses)
    assert fam.count(1) == 0
    np.testing.assert_allclose(abs(fam.unit @ [1.0, 0.0]), 1.0, atol=1e-3)
    seg = fam.segment(0)
    assert seg.length == pytest.approx(5.0, abs=0.02)
    ends = seg.ends[:, 0]
    assert sorted(ends) == pytest.approx([2.0, 7.0], abs=0.02)
    assert seg.heading == pytest.approx(0.4, abs=1e-9)
    assert fam.spread < 0.05


def test_two_headings_half_a_turn_apart_are_the_two_classes() -> None:
    poses = _corridor_poses()
    fam = axis_family(poses)
    assert fam is not None
    assert (fam.count(0), fam.count(1)) == (9, 9)
    assert fam.headings[0] == pytest.approx(TRUTH[2])
    assert float(wrap_angle(fam.headings[1] - FLIPPED)) == pytest.approx(0.0, abs=1e-9)
    # the classes lie on their own lines, 0.6 m apart: the spread is about each class' line
    assert fam.spread < 1e-9
    np.testing.assert_allclose(fam.points[:, 1], [0.3, -0.3])
    for c in (0, 1):
        assert fam.segment(c).length == pytest.approx(4.0)


def test_a_squares_four_copies_are_not_an_axis() -> None:
    centre = np.array([2.0, 1.0])
    pose = np.array([2.5, 1.2, 0.3])
    copies = []
    for k in range(4):
        a = k * math.pi / 2
        c, s = math.cos(a), math.sin(a)
        xy = centre + np.array([[c, -s], [s, c]]) @ (pose[:2] - centre)
        copies.append([xy[0], xy[1], pose[2] + a])
    assert axis_family(np.array(copies)) is None
    # two opposite copies (a rectangle's) are too few for an axis
    assert axis_family(np.array(copies)[[0, 2]]) is None


def test_scattered_or_clumped_poses_are_not_an_axis() -> None:
    rng = np.random.default_rng(1)
    scattered = np.column_stack([rng.uniform(0, 5, (8, 2)), np.full(8, 0.2)])
    assert axis_family(scattered) is None
    clumped = _line(np.linspace(3.0, 3.4, 5), 0.0, 0.2)
    assert axis_family(clumped) is None
    turned = _line(np.arange(0.0, 4.0, 0.5), 0.0, 0.0)
    turned[3, 2] = math.radians(25.0)  # one heading off by 25 deg: not one heading
    assert axis_family(turned) is None


def test_sweep_finds_where_the_scan_fits_along_the_line() -> None:
    seg = AxisSegment(np.array([8.0, 0.33]), np.array([1.0, 0.0]), 0.1, -1.0, 1.0)

    def score(poses: np.ndarray) -> np.ndarray:
        inside = (poses[:, 0] >= 2.0) & (poses[:, 0] <= 18.0)
        on_line = np.abs(poses[:, 1] - 0.3) < 0.03
        return np.where(inside & on_line, 0.9, 0.1)

    found = sweep(score, seg, -20.0, 20.0)
    assert found is not None
    out, share = found
    assert out.point[1] == pytest.approx(0.33 - 0.05)  # moved onto the best offset
    assert out.lo == pytest.approx(-6.0, abs=0.1)
    assert out.hi == pytest.approx(10.0, abs=0.1)
    assert share == pytest.approx(1.0)
    assert sweep(lambda p: np.zeros(len(p)), seg, -5.0, 5.0) is None

    def pillars(poses: np.ndarray) -> np.ndarray:
        # repeated features every 2 m: the scan fits only near x = 2, 4, ..., 18 m
        near = np.abs((poses[:, 0] + 1.0) % 2.0 - 1.0) < 0.15
        return np.where(near & (np.abs(poses[:, 1] - 0.3) < 0.03), 0.9, 0.1)

    found = sweep(pillars, seg, -20.0, 20.0)
    assert found is not None
    assert found[1] < 0.3  # gaps between the pillars: not a corridor's continuous stretch


def _corridor_grid(open_end: bool, specks: bool = False, pillar: bool = False) -> OccupancyGrid:
    """20 m x 2 m corridor along x in a 22 m x 4 m grid (5 cm cells): walls occupied, the
    inside free, the outside unknown; ``open_end`` leaves x > 15 m unmapped; ``pillar`` puts
    a 30 cm pillar on the line y = 0.3 m at x = 13 m."""
    res = 0.05
    data = np.full((80, 440), -1, np.int8)  # rows: y from -2 m, cols: x from -1 m
    x = -1.0 + (np.arange(440) + 0.5) * res
    y = -2.0 + (np.arange(80) + 0.5) * res
    inside = (np.abs(y)[:, None] < 1.0) & (x[None, :] > 0.0) & (x[None, :] < 20.0)
    wall = (np.abs(y)[:, None] < 1.1) & (x[None, :] > -0.1) & (x[None, :] < 20.1) & ~inside
    data[wall] = 100
    data[inside] = 0
    if pillar:
        data[np.ix_(np.abs(y - 0.3) < 0.15, np.abs(x - 13.0) < 0.15)] = 100
    if open_end:
        data[:, x > 15.0] = -1
        if specks:
            data[40, (x > 15.0) & (x < 15.1)] = 100
    return OccupancyGrid(data, res, np.array([-1.0, -2.0, 0.0]))


def test_an_end_wall_closes_the_line_and_unmapped_space_opens_it() -> None:
    seg = AxisSegment(np.array([8.0, 0.3]), np.array([1.0, 0.0]), 0.1, -4.0, 4.0)
    closed = _corridor_grid(open_end=False)
    assert not runs_out(seg, closed, seg.hi, +1)
    assert not runs_out(seg, closed, seg.lo, -1)
    opened = _corridor_grid(open_end=True, specks=True)
    assert runs_out(seg, opened, seg.hi, +1)  # a speck is no end wall
    assert not runs_out(seg, opened, seg.lo, -1)
    # a pillar on the line is no end wall either, open or closed beyond it
    assert runs_out(seg, _corridor_grid(open_end=True, pillar=True), seg.hi, +1)
    assert not runs_out(seg, _corridor_grid(open_end=False, pillar=True), seg.hi, +1)


def test_the_axis_covariance_covers_the_whole_segment() -> None:
    seg = AxisSegment(np.array([8.0, 0.3]), np.array([0.6, 0.8]), 0.1, -5.0, 7.0)
    cov = axis_covariance(seg, 0.05, math.radians(1.0))
    middle = seg.middle()
    for end in seg.ends:
        e = np.array([*(end - middle[:2]), 0.0])
        assert nees(e, cov) == pytest.approx(3.0)  # (L/2)^2 / (L^2 / 12)
        assert nees(e + np.array([0.0, 0.0, math.radians(1.5)]), cov) < CHI2_3DOF_95
    # tight across: 20 cm off the line is far outside
    across = np.array([*(0.2 * seg.normal), 0.0])
    assert nees(across, cov) > CHI2_3DOF_95
    np.testing.assert_allclose(np.linalg.eigvalsh(cov[:2, :2])[-1], 12.0**2 / 12.0)


# --------------------------------------------------------------------------- the camera


def _verification(statuses, inliers, offsets, margin=2.0) -> Verification:
    checks = tuple(
        HypothesisVerdict(s, n, o) for s, n, o in zip(statuses, inliers, offsets, strict=True)
    )
    return Verification(None, None, "", {}, checks, margin, math.radians(15.0))


def test_the_camera_decides_the_heading_class_with_margin() -> None:
    poses = np.vstack([_line([7, 8, 9], 0.3, 0.1), _line([7, 8, 9], -0.3, 0.1 + math.pi)])
    classes = np.array([0, 0, 0, 1, 1, 1])
    nan = math.nan
    # several of the right class verify (no single hypothesis is verified with margin)
    ver = _verification(["verified", "verified", "contradicted"] + ["contradicted"] * 3,
                        [60, 45, 3, 8, 0, 5], [0.01, -0.02, nan, 0.5, nan, 1.0])  # fmt: skip
    vote = vote_heading(poses, classes, ver, min_inliers=30)
    assert vote.winner == 0
    assert vote.best == (60, 0)
    assert vote.rival == 8
    assert vote.heading == pytest.approx(0.11)
    # the half-turned class fits with 40: 60 < 2 x 40, not decided
    close = _verification(["verified", "unknown", "unknown", "contradicted", "unknown", "unknown"],
                          [60, 0, 0, 40, 0, 0], [0.0, nan, nan, 0.4, nan, nan])  # fmt: skip
    vote = vote_heading(poses, classes, close, min_inliers=30)
    assert vote.winner is None
    assert "margin" in vote.reason
    # one weak match never decides
    weak = _verification(["verified"] + ["unknown"] * 5, [26, 0, 0, 0, 0, 0], [0.0] + [nan] * 5)
    assert vote_heading(poses, classes, weak, min_inliers=30).winner is None
    # a half-turned hypothesis whose fit measures the winner's heading is evidence, no rival
    agree = _verification(["verified", "unknown", "unknown", "contradicted", "unknown", "unknown"],
                          [60, 0, 0, 40, 0, 0], [0.0, nan, nan, -math.pi, nan, nan])  # fmt: skip
    assert vote_heading(poses, classes, agree, min_inliers=30).winner == 0
    # ... unless that fit is on a keyframe no verified hypothesis of the winner should see
    look_alike = Verification(
        None,
        None,
        "",
        {},
        (
            HypothesisVerdict("verified", 60, 0.0, 3, (3, 4)),
            *agree.checks[1:3],
            HypothesisVerdict("contradicted", 40, -math.pi, 9, (9,)),
            *agree.checks[4:],
        ),
        2.0,
        math.radians(15.0),
    )
    assert vote_heading(poses, classes, look_alike, min_inliers=30).winner is None
    seen = dataclasses.replace(look_alike.checks[3], keyframe=4)
    checks = (*look_alike.checks[:3], seen, *look_alike.checks[4:])
    assert vote_heading(poses, classes, dataclasses.replace(look_alike, checks=checks),
                        min_inliers=30).winner == 0  # fmt: skip
    # both classes verified alike: no decision
    both = _verification(["verified", "unknown", "unknown", "verified", "unknown", "unknown"],
                         [60, 0, 0, 55, 0, 0], [0.0, nan, nan, 0.0, nan, nan])  # fmt: skip
    assert vote_heading(poses, classes, both, min_inliers=30).winner is None
    # a store that gives no per-hypothesis checks decides nothing
    bare = Verification(0, poses[0], "scripted", {})
    assert vote_heading(poses, classes, bare, min_inliers=30).winner is None


# --------------------------------------------------------------------------- the localizer


@dataclass
class CorridorScore:
    """The scan fits on the class lines (y = +-0.3 m) facing along the corridor either way, the
    forward class between ``lo`` and ``hi`` [m] in x, the half-turned one mirrored about
    x = 10 m (as a featureless corridor's scan does: 2-18 m, the ends out of sight)."""

    lo: float = 2.0
    hi: float = 18.0

    def __call__(self, poses: np.ndarray, scan: object) -> np.ndarray:
        p = np.asarray(poses, float).reshape(-1, 3)
        fwd = np.abs(wrap_angle(p[:, 2] - TRUTH[2])) < math.radians(5)
        back = np.abs(wrap_angle(p[:, 2] - FLIPPED)) < math.radians(5)
        x = p[:, 0]
        fwd &= (np.abs(p[:, 1] - 0.3) < 0.03) & (x >= self.lo) & (x <= self.hi)
        back &= (np.abs(p[:, 1] + 0.3) < 0.03) & (20.0 - x >= self.lo) & (20.0 - x <= self.hi)
        return np.where(fwd | back, 0.95, 0.05)


@dataclass
class CorridorKeyframes:
    """Keyframes along the corridor looking along +x (heading 0.1): a hypothesis with that
    heading within 1.5 m of the truth verifies; the half-turned ones are contradicted."""

    truth: np.ndarray = field(default_factory=lambda: TRUTH.copy())
    shown: list[np.ndarray] = field(default_factory=list)
    reaches: list[float] = field(default_factory=list)
    facing: float = TRUTH[2]
    #: keyframes expected by every pose (the view planner never turns the robot)
    everywhere: bool = False

    def keyframe_count(self) -> int:
        return 20

    def expected_counts(self, poses: np.ndarray, reach: float = 0.0) -> np.ndarray:
        """The corridor was mapped both ways: keyframes along the axis, either way."""
        th = np.asarray(poses, float).reshape(-1, 3)[:, 2]
        if self.everywhere:
            return np.full(th.shape, 2, np.int64)
        off = np.abs(np.asarray(wrap_angle(th - self.facing), float))
        along = (off <= math.radians(40)) | (off >= math.pi - math.radians(40))
        return along.astype(np.int64) * 2

    def verify(
        self,
        poses: np.ndarray,
        image: np.ndarray,
        reach: float = 0.0,
        *,
        refine: bool = False,
        round_centre: object = None,
    ) -> Verification:
        poses = np.asarray(poses, float)
        self.shown.append(poses.copy())
        self.reaches.append(reach)
        checks = []
        for p in poses:
            right = abs(float(wrap_angle(p[2] - self.facing))) < math.radians(10)
            near = math.hypot(*(p[:2] - self.truth[:2])) < 1.5
            if right and near:
                checks.append(HypothesisVerdict("verified", 80, 0.0))
            else:
                checks.append(HypothesisVerdict("contradicted", 4, math.nan))
        verified = [i for i, c in enumerate(checks) if c.verified]
        index = verified[0] if len(verified) == 1 else None
        pose = None if index is None else poses[index]
        return Verification(index, pose, "scripted", {}, tuple(checks), 2.0, math.radians(15))


class SpreadTracker(FakeTracker):
    """AMCL spread along the corridor after a reseed: never converged."""

    def initialize_pose(self, pose, covariance) -> None:
        self.seeded.append(np.asarray(pose, float))
        self.default = _result([pose], [1.0], std=3.0)


def _corridor_localizer(
    tracker: FakeTracker, proposer: FakeProposer, keyframes, score=None, **cfg
) -> Localizer:
    """One image decides the heading class unless ``axis_views`` says otherwise (the
    scripted keyframes answer the same at every heading)."""
    cfg.setdefault("axis_views", 1)
    config = LocalizerConfig(decide_here=True, **cfg)
    loc = Localizer(
        tracker,
        SquareJudge(symmetric=False),
        FakeStore(),
        config,
        scorer=CorridorScore() if score is None else score,
        proposer=proposer,
        keyframes=keyframes,
    )
    loc.reset_global()
    return loc


def _step(loc: Localizer, odom=(0.0, 0.0, 0.0), image=None) -> Estimate:
    return loc.update(OdometryReading(np.asarray(odom, float)), TRUTH.copy(), image)


def _spread() -> SpreadTracker:
    return SpreadTracker(default=_result([TRUTH], [1.0], std=3.0))


def test_in_a_corridor_the_camera_decides_the_heading_and_the_position_stays_open() -> None:
    kf = CorridorKeyframes()
    tracker = _spread()
    loc = _corridor_localizer(tracker, FakeProposer(list(_corridor_poses()), complete=False), kf)
    est = _step(loc)
    assert est.status is Status.DECIDING
    assert est.request is not None
    assert est.request.kind is RequestKind.CAPTURE_IMAGE
    est = _step(loc, image=IMAGE)
    # both classes were shown, along the whole stretch where the scan fits (2-18 m)
    shown = kf.shown[0]
    assert shown[:, 0].min() == pytest.approx(2.0, abs=0.1)
    assert shown[:, 0].max() == pytest.approx(18.0, abs=0.1)
    assert {round(float(wrap_angle(h - TRUTH[2])), 3) for h in shown[:, 2]} == {0.0, 3.142}
    # the truth lies between two samples: each one's keyframes reach half the spacing further
    spacing = float(np.max(np.abs(np.diff(np.sort(shown[: len(shown) // 2, 0])))))
    assert kf.reaches[0] == pytest.approx(0.5 * spacing)
    assert kf.reaches[0] > 0.0
    assert est.status is Status.AXIS
    assert est.pose is None  # nothing claimed
    assert est.covariance is None
    axis = est.axis
    assert isinstance(axis, AxisPose)
    assert axis.pose[2] == pytest.approx(TRUTH[2])
    assert axis.pose[:2] == pytest.approx([10.0, 0.3], abs=0.1)
    assert axis.length == pytest.approx(16.0, abs=0.2)
    assert math.sqrt(axis.covariance[0, 0]) == pytest.approx(16.0 / math.sqrt(12.0), rel=0.02)
    # across: the hypotheses' scatter (none here: 5 cm, the least) and the line's direction
    # error (0.3 deg) 8 m from the middle of the stretch it was fitted on
    across = math.hypot(0.05, math.radians(0.3) * 8.0)
    assert math.sqrt(axis.covariance[1, 1]) == pytest.approx(across, rel=0.02)
    assert nees(TRUTH - axis.pose, axis.covariance) < CHI2_3DOF_95
    assert loc.phase == "axis"
    assert loc.decide_counts.axis == 1
    np.testing.assert_allclose(tracker.seeded[-1], axis.pose)
    # it stays: the segment carried by odometry (1 m forward along the heading)
    odom = np.array([1.0, 0.0, 0.0])
    est = _step(loc, odom=odom)
    assert est.status is Status.AXIS
    assert est.axis is not None
    moved = est.axis.pose[:2] - axis.pose[:2]
    np.testing.assert_allclose(moved, [math.cos(0.1), math.sin(0.1)], atol=1e-9)
    assert est.axis.length == pytest.approx(axis.length + 2 * 0.05)


def test_the_axis_is_renewed_by_the_laser_without_an_image() -> None:
    kf = CorridorKeyframes()
    loc = _corridor_localizer(
        _spread(), FakeProposer(list(_corridor_poses()), complete=False), kf, axis_recheck=2
    )
    _step(loc)
    est = _step(loc, image=IMAGE)
    assert est.status is Status.AXIS
    for _ in range(8):
        est = _step(loc)
        assert est.status is Status.AXIS
        assert est.request is None
    assert len(kf.shown) == 1  # no second image: the laser's axis has the decided heading
    assert loc.decide_counts.entered >= 3


def test_the_heading_class_needs_two_views_that_agree() -> None:
    kf = CorridorKeyframes(everywhere=True)
    tracker = _spread()
    proposer = FakeProposer(list(_corridor_poses()), complete=False)
    loc = _corridor_localizer(tracker, proposer, kf, axis_views=2)
    _step(loc)
    est = _step(loc, image=IMAGE)
    # the first image decides the class, but alone it is not enough: look elsewhere
    assert est.status is Status.DECIDING
    assert est.request is not None
    assert est.request.kind is RequestKind.ROTATE
    assert "1 of 2 views agree" in loc.log[-1] or any("1 of 2 views agree" in s for s in loc.log)
    # the driver turns; the scripted laser proposes the same map poses, the camera agrees
    odom = (0.0, 0.0, est.request.angle)
    est = _step(loc, odom=odom)
    assert est.request is not None
    assert est.request.kind is RequestKind.CAPTURE_IMAGE
    est = _step(loc, odom=odom, image=IMAGE)
    assert est.status is Status.AXIS
    assert len(kf.shown) == 2


@dataclass
class OnceKeyframes(CorridorKeyframes):
    """Keyframes that verify the right class at the images ``seen`` (call numbers, from 0) and
    nothing at the others (every hypothesis contradicted)."""

    seen: tuple[int, ...] = ()
    calls: int = 0

    def verify(self, poses, image, reach=0.0, *, refine=False, round_centre=None):  # type: ignore[no-untyped-def]
        self.facing = TRUTH[2] if self.calls in self.seen else TRUTH[2] + 0.5 * math.pi
        self.calls += 1
        return super().verify(poses, image, reach, refine=refine, round_centre=round_centre)


def _drive(loc: Localizer, est: Estimate, heading: float, until, limit: int = 80):  # type: ignore[no-untyped-def]
    """Carry out the localizer's turns and give it images until ``until(est)``; the last
    estimate and odometry heading."""
    for _ in range(limit):
        if until(est):
            break
        req = est.request
        if req is not None and req.kind is RequestKind.ROTATE:
            assert req.angle is not None
            heading += req.angle
        image = IMAGE if req is not None and req.kind is RequestKind.CAPTURE_IMAGE else None
        est = _step(loc, odom=(0.0, 0.0, heading), image=image)
    return est, heading


def test_a_vote_from_an_earlier_episode_counts_towards_the_heading_class() -> None:
    # the first image decides the class, the episode's other three verify nothing and it gives
    # up; the next episode's first image, taken at another heading, decides the same class and
    # its other views again nothing: the two views agree across the episodes
    kf = OnceKeyframes(everywhere=True, seen=(0, 4))
    proposer = FakeProposer(list(_corridor_poses()), complete=False)
    loc = _corridor_localizer(_spread(), proposer, kf, axis_views=2, decide_rest=3)
    est, _ = _drive(loc, _step(loc), 0.0, lambda e: kf.calls == 4)
    assert any("1 of 2 views agree" in s for s in loc.log)
    assert any(s.startswith("not decided here") for s in loc.log)
    assert loc.decide_counts.axis == 0
    # the scripted laser proposes the same map poses whatever odometry says: odometry turned
    # 45 deg since the first vote (another view; its rotation within the class' half turn)
    est, _ = _drive(loc, est, math.radians(45.0), lambda e: e.status is Status.AXIS)
    assert est.status is Status.AXIS
    assert kf.calls == 5  # decided at the second episode's first image
    assert loc.decide_counts.axis == 1
    # after a reset (a kidnapping, start-up) an earlier vote counts for nothing
    kf = OnceKeyframes(everywhere=True, seen=(0, 4))
    proposer = FakeProposer(list(_corridor_poses()), complete=False)
    loc = _corridor_localizer(_spread(), proposer, kf, axis_views=2, decide_rest=3)
    est, _ = _drive(loc, _step(loc), 0.0, lambda e: kf.calls == 4)
    loc.reset_global()
    _drive(loc, est, math.radians(45.0), lambda e: kf.calls == 6)
    assert kf.calls == 6
    assert loc.decide_counts.axis == 0


def test_views_that_disagree_on_the_heading_class_decide_nothing() -> None:
    kf = CorridorKeyframes(everywhere=True)
    proposer = FakeProposer(list(_corridor_poses()), complete=False)
    loc = _corridor_localizer(_spread(), proposer, kf, axis_views=2)
    _step(loc)
    est = _step(loc, image=IMAGE)
    assert est.request is not None
    odom = (0.0, 0.0, est.request.angle)
    # the same map poses after the turn, but the camera now sees the other class: a robot
    # whose odometry turned while the map heading it verifies did not
    kf.facing = TRUTH[2] + math.pi
    _step(loc, odom=odom)
    est = _step(loc, odom=odom, image=IMAGE)
    assert est.status is not Status.AXIS
    assert any("disagree on the heading class" in s for s in loc.log)
    assert loc.decide_counts.axis == 0


def test_an_undecided_heading_is_not_an_axis() -> None:
    # keyframes expected here, but none looks either way along the axis
    kf = CorridorKeyframes(facing=TRUTH[2] + math.pi / 2, everywhere=True)
    loc = _corridor_localizer(
        _spread(), FakeProposer(list(_corridor_poses()), complete=False), kf, decide_views=1
    )
    _step(loc)
    est = _step(loc, image=IMAGE)
    assert est.status is Status.LOST
    assert "heading not decided" in est.reason
    assert loc.decide_counts.axis == 0


def test_the_axis_never_blocks_the_normal_path() -> None:
    kf = CorridorKeyframes()
    tracker = FakeTracker(default=_result([TRUTH], [1.0], std=3.0))  # converges once reseeded
    loc = _corridor_localizer(tracker, FakeProposer(list(_corridor_poses()), complete=False), kf)
    _step(loc)
    assert _step(loc, image=IMAGE).status is Status.AXIS
    statuses = [_step(loc).status for _ in range(5)]
    # AMCL converged (scripted, no claim gate): the lost phase's path publishes it
    assert statuses[-1] is Status.TRACKING
    assert loc.phase == "tracking"


def test_a_pose_verified_against_the_axis_heading_is_refused() -> None:
    kf = CorridorKeyframes()
    proposer = FakeProposer(list(_corridor_poses()), complete=False)
    score = CorridorScore()
    loc = _corridor_localizer(_spread(), proposer, kf, score, axis_recheck=1)
    _step(loc)
    assert _step(loc, image=IMAGE).status is Status.AXIS
    # an end comes into view: two mirrored poses; the camera verifies the half-turned one
    end = np.array([16.0, 0.3, TRUTH[2]])
    mirror = np.array([4.0, -0.3, FLIPPED])
    proposer.poses = [end, mirror]
    score.lo = score.hi = 16.0
    kf.truth, kf.facing = np.array([4.0, -0.3, 0.0]), FLIPPED
    for _ in range(5):
        est = _step(loc)
        if est.request is not None and est.request.kind is RequestKind.CAPTURE_IMAGE:
            break
    assert est.request is not None
    assert est.request.kind is RequestKind.CAPTURE_IMAGE
    assert est.status is Status.AXIS  # deciding from the axis: still reported
    est = _step(loc, image=IMAGE)
    assert est.status is not Status.TRACKING
    assert "faces against the axis" in " ".join(loc.log[-3:])


def test_an_end_in_view_lets_the_camera_earn_the_pose_with_the_axis_heading() -> None:
    kf = CorridorKeyframes()
    proposer = FakeProposer(list(_corridor_poses()), complete=False)
    score = CorridorScore()
    loc = _corridor_localizer(_spread(), proposer, kf, score, axis_recheck=1)
    _step(loc)
    assert _step(loc, image=IMAGE).status is Status.AXIS
    end = np.array([16.0, 0.3, TRUTH[2]])
    proposer.poses = [end, np.array([4.0, -0.3, FLIPPED])]
    score.lo = score.hi = 16.0
    kf.truth = end
    for _ in range(5):
        est = _step(loc)
        if est.request is not None and est.request.kind is RequestKind.CAPTURE_IMAGE:
            break
    est = _step(loc, image=IMAGE)
    assert est.status is Status.TRACKING  # no claim gate in this scripted test
    np.testing.assert_allclose(est.pose, end)


def test_an_axis_running_into_unmapped_space_is_lengthened_there() -> None:
    kf = CorridorKeyframes()
    config = LocalizerConfig(decide_here=True, axis_open_reach=10.0, axis_views=1)
    score = CorridorScore(lo=2.0, hi=14.0)  # the map stops at 15 m: the scan fits up to 14 m
    loc = Localizer(
        _spread(),
        SquareJudge(symmetric=False),
        FakeStore(),
        config,
        scorer=score,
        proposer=FakeProposer(list(_corridor_poses()), complete=False),
        keyframes=kf,
        grid=_corridor_grid(open_end=True),
    )
    loc.reset_global()
    _step(loc)
    est = _step(loc, image=IMAGE)
    assert est.status is Status.AXIS
    assert est.axis is not None
    assert est.axis.open_ends == 1
    xs = sorted(est.axis.ends[:, 0])
    assert xs[0] == pytest.approx(2.0, abs=0.1)  # the end wall closes the line at 0 m
    assert xs[1] == pytest.approx(21.0 + 10.0, abs=0.1)  # the grid's edge, and 10 m beyond
    # the camera was shown only where the scan fits the map
    shown = kf.shown[0]
    forward = np.abs(wrap_angle(shown[:, 2] - TRUTH[2])) < 0.1
    assert shown[forward, 0].max() == pytest.approx(14.0, abs=0.1)


def test_repeated_features_along_a_line_are_left_to_the_camera_one_by_one() -> None:
    class Pillars(CorridorScore):
        def __call__(self, poses: np.ndarray, scan: object) -> np.ndarray:
            out = super().__call__(poses, scan)
            x = np.asarray(poses, float).reshape(-1, 3)[:, 0]
            return np.where(np.abs((x + 1.0) % 2.0 - 1.0) < 0.15, out, 0.05)

    poses = np.vstack([_line([6.0, 8.0, 10.0], 0.3, TRUTH[2]), _line([10.0, 12.0], -0.3, FLIPPED)])
    kf = CorridorKeyframes()
    loc = _corridor_localizer(_spread(), FakeProposer(list(poses), complete=False), kf, Pillars())
    est = _step(loc)
    assert "along an axis" not in loc.log[-1]
    assert est.request is not None
    assert est.request.kind is RequestKind.CAPTURE_IMAGE
    est = _step(loc, image=IMAGE)
    # the camera verified the one at the truth: the decide path's usual claim
    assert est.status is Status.TRACKING
    np.testing.assert_allclose(est.pose, TRUTH)


def test_axis_estimates_carry_an_axis_and_nothing_else_does() -> None:
    pose = AxisPose(np.zeros(3), np.eye(3), np.array([[0.0, 0.0], [1.0, 0.0]]))
    Estimate(Status.AXIS, axis=pose)
    with pytest.raises(ConfigurationError, match="axis"):
        Estimate(Status.AXIS)
    with pytest.raises(ConfigurationError, match="axis"):
        Estimate(Status.LOST, axis=pose)
    with pytest.raises(ConfigurationError, match="pose"):
        Estimate(Status.AXIS, pose=np.zeros(3), covariance=np.eye(3), axis=pose)
    with pytest.raises(ConfigurationError, match="ends"):
        AxisPose(np.zeros(3), np.eye(3), np.zeros((3, 2)))
    with pytest.raises(ConfigurationError, match="axis_sweep_ratio"):
        LocalizerConfig(axis_sweep_ratio=1.5)


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("axis_views", 0),
        ("axis_views", 1.5),
        ("axis_min_inliers", 0),
        ("copy_map_slack", -0.1),
        ("copy_claim_floor", "yes"),
        ("decide_turn", -1.0),
        ("decide_watch_evidence", 0.0),
        ("decide_watch_views", 0),
        ("decide_rest_no_camera", 0),
        ("decide_rest_no_camera", "20"),
        ("decide_rest_no_camera", 2.5),
    ],
)
def test_bad_decide_settings_are_refused_by_name(field: str, value: object) -> None:
    with pytest.raises(ConfigurationError, match=f"LocalizerConfig.{field}"):
        LocalizerConfig(**{field: value})


def test_an_axis_heading_carried_through_an_unconfirmed_turn_is_held_back() -> None:
    """The heading's std grows with the turning the laser has not confirmed, by the robot's
    rotation error (the gate's alpha1); past the gate's bound nothing is reported (deciding
    here keeps its request), and a confirmation reports the axis again."""
    from types import SimpleNamespace

    from symloc.localizer.axis import AxisSegment
    from symloc.localizer.axis_phase import OnAxis
    from symloc.localizer.claim import ClaimConfig
    from symloc.localizer.phases import Lost
    from symloc.localizer.types import Request

    cfg = LocalizerConfig(decide_here=True)
    claim = ClaimConfig()
    heavy = SimpleNamespace(alphas=(0.022, 0.0005, 0.004, 0.0004), config=claim)
    ctx = SimpleNamespace(config=cfg, gate=heavy)
    inp = SimpleNamespace(result=_result([TRUTH], [1.0]))
    segment = AxisSegment(np.array([2.0, 0.3]), np.array([1.0, 0.0]), 0.0, 0.0, 16.0)
    axis = OnAxis(
        segment, TRUTH.copy(), np.zeros(3), 0, 0.05, Lost.fresh(cfg), "heading class 1 verified"
    )
    est = axis.report(ctx, inp, axis.headline())  # type: ignore[arg-type]
    assert est.status is Status.AXIS
    assert est.axis is not None
    assert math.sqrt(est.axis.covariance[2, 2]) == pytest.approx(cfg.axis_theta_std)
    # odometry turns 3 deg: std sqrt(1 + 0.022 * 3^2) deg, still inside 1.25 deg, and reported so
    axis.carry(ctx, np.array([0.0, 0.0, math.radians(3.0)]))  # type: ignore[arg-type]
    est = axis.report(ctx, inp, axis.headline())  # type: ignore[arg-type]
    assert est.status is Status.AXIS
    assert est.axis is not None
    grown = math.hypot(cfg.axis_theta_std, math.sqrt(0.022) * math.radians(3.0))
    assert math.sqrt(est.axis.covariance[2, 2]) == pytest.approx(grown)
    assert grown < claim.max_std_theta
    # 60 deg more (deciding here turning to look elsewhere): 9 deg std, held back
    axis.carry(ctx, np.array([0.0, 0.0, math.radians(63.0)]))  # type: ignore[arg-type]
    turn = Request(RequestKind.ROTATE, angle=math.radians(60.0))
    est = axis.report(ctx, inp, "deciding here: turning", turn)  # type: ignore[arg-type]
    assert est.status is Status.DECIDING
    assert est.axis is None
    assert est.request is turn
    assert "axis held" in est.reason
    # the robot's default rotation error (5 % of a turn) holds it back only past 15 deg
    calm = SimpleNamespace(alphas=claim.odometry_alphas, config=claim)
    axis.turned = math.radians(14.0)
    assert axis.report(SimpleNamespace(config=cfg, gate=calm), inp, "").status is Status.AXIS  # type: ignore[arg-type]
    axis.turned = math.radians(16.0)
    assert axis.report(SimpleNamespace(config=cfg, gate=calm), inp, "").status is Status.LOST  # type: ignore[arg-type]
    # the laser proposing the axis again confirms it
    chosen = SimpleNamespace(segment=segment, reference=TRUTH.copy(), open_ends=0, across_std=0.05)
    axis.renew(chosen, np.zeros(3))  # type: ignore[arg-type]
    assert axis.report(ctx, inp, "").status is Status.AXIS  # type: ignore[arg-type]
