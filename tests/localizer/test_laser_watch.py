"""The laser watching several hypotheses as the robot moves (symloc.localizer.laser_watch)."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
import pytest

from symloc.geometry import compose, wrap_angle
from symloc.lidar_spec import LDS01
from symloc.localizer import Status
from symloc.localizer.build import build_localizer
from symloc.localizer.config import LocalizerConfig
from symloc.localizer.laser_watch import (
    MIN_VIEWS,
    STILL_SCANS,
    VIEW_ALLOWANCE,
    VIEW_STEP,
    LaserWatch,
)
from symloc.localizer.settings import LocalizerSettings
from symloc.localizer.types import KeyframeStore, Verification
from symloc.odometry import OdometryReading
from symloc.scan import LaserScan
from symloc.sim.lidar import simulate_scan
from symloc.sim.rasterize import world_to_grid
from symloc.sim.rooms import add_furniture, rectangle_room

TRUE = np.array([1.0, 0.5, 0.3])
COPY = np.array([-1.0, -0.5, 0.3 - math.pi])
SCAN = LaserScan(
    ranges=np.ones(8), angle_min=0.0, angle_increment=0.1, range_min=0.1, range_max=5.0
)


@dataclass
class FakeGate:
    """Fits by which hypothesis a pose is (near TRUE's half of the room or COPY's)."""

    true_fit: float
    copy_fit: float
    true_loose: float = 1.0
    copy_loose: float = 1.0

    def _true(self, pose: np.ndarray) -> bool:
        return float(pose[0]) > 0.0

    def fit(self, pose: np.ndarray, scan: object) -> tuple[np.ndarray, float]:
        return np.asarray(pose, float), self.true_fit if self._true(pose) else self.copy_fit

    def share_within(self, pose: np.ndarray, scan: object, distance: float) -> float:
        return self.true_loose if self._true(pose) else self.copy_loose


def _watch(
    gate: FakeGate, steps: int, *, move: float = 1.5 * VIEW_STEP
) -> list[tuple[int | None, bool]]:
    w = LaserWatch(np.array([COPY, TRUE]), np.zeros(3), slack=0.3, evidence=0.5)
    out = []
    for i in range(steps):
        v = w.step(gate, SCAN, np.array([move * (i + 1), 0.0, 0.0]))  # type: ignore[arg-type]
        out.append((v.leader, v.decided))
    return out


def test_a_rival_short_of_beams_at_every_view_is_ruled_out() -> None:
    gate = FakeGate(0.95, 0.90, 1.0, 0.95)  # 5 % fewer beams, tight and loose, at every view
    per_view = 0.05 - VIEW_ALLOWANCE
    need = max(MIN_VIEWS, math.ceil(0.5 / per_view - 1e-9))
    out = _watch(gate, need + 2)
    assert all(leader == 1 for leader, _ in out)
    first = next(i for i, (_, decided) in enumerate(out) if decided)
    assert first + 1 == need


def test_equal_copies_are_never_decided() -> None:
    assert not any(d for _, d in _watch(FakeGate(0.95, 0.95), 200))


def test_a_bias_within_the_allowance_never_adds_up() -> None:
    gate = FakeGate(0.95, 0.95 - 0.9 * VIEW_ALLOWANCE, 1.0, 1.0 - 0.9 * VIEW_ALLOWANCE)
    assert not any(d for _, d in _watch(gate, 300))


def test_the_loose_share_must_tell_them_apart_too() -> None:
    # the copy misses beams by centimetres only (a map error's size): not ruled out
    assert not any(d for _, d in _watch(FakeGate(0.95, 0.80, 1.0, 1.0), 100))


def test_standing_still_is_one_view() -> None:
    out = _watch(FakeGate(0.95, 0.5, 1.0, 0.5), 50, move=0.0)
    assert not any(d for _, d in out)
    w = LaserWatch(np.array([COPY, TRUE]), np.zeros(3), slack=0.3, evidence=0.5)
    for _ in range(10):
        w.step(FakeGate(0.95, 0.5), SCAN, np.zeros(3))  # type: ignore[arg-type]
    assert w.views == 1


def test_hypotheses_are_carried_by_odometry() -> None:
    w = LaserWatch(np.array([TRUE]), np.array([0.0, 0.0, 0.0]), slack=0.0, evidence=0.5)
    w.step(FakeGate(1.0, 1.0), SCAN, np.array([1.0, 0.0, 0.0]))  # type: ignore[arg-type]
    want = compose(TRUE, np.array([1.0, 0.0, 0.0]))
    np.testing.assert_allclose(w.poses[0], want)


class _KeyframesOutOfView:
    """A visual map whose keyframes no pose of this room sees (the camera is done at once)."""

    def keyframe_count(self) -> int:
        return 5

    def expected_counts(self, poses: np.ndarray, reach: float = 0.0) -> np.ndarray:
        return np.zeros(len(poses), np.int64)

    def verify(
        self,
        poses: np.ndarray,
        image: np.ndarray,
        reach: float = 0.0,
        *,
        refine: bool = False,
        round_centre: object = None,
    ) -> Verification:
        raise AssertionError("no image is asked for: no keyframe is in view")


def _drive(
    boxes: int,
    scans: int,
    keyframes: KeyframeStore | None = None,
    truths: list[np.ndarray] | None = None,
) -> list[tuple[Status, float, str]]:
    """A TurtleBot3-like robot (laser 3.2 cm behind the base) on a 1 m circle in a 5 m x 3.6 m
    room, no initial pose and no keyframes (or ``keyframes``): (status, position error [m],
    reason) per scan; each scan's true pose (3,) appended to ``truths`` as it is taken."""
    room = rectangle_room(5.0, 3.6)
    world = add_furniture(room, boxes=boxes, rng=3).world if boxes else room.world
    grid = world_to_grid(world, 0.05, free_seeds=[[0.0, -0.4]])
    laser = np.array([-0.032, 0.0, 0.0])
    settings = LocalizerSettings(laser_pose=(-0.032, 0.0, 0.0), seed=1)
    loc = build_localizer(grid, settings, keyframes=keyframes)
    loc.reset_global()
    rng = np.random.default_rng(4)
    truth, odom = np.array([0.0, -1.4, 0.0]), np.zeros(3)
    out = []
    dt, v, w = 0.2, 0.25, 0.25

    def step(p: np.ndarray, v: float, w: float) -> np.ndarray:
        th = p[2] + 0.5 * w * dt
        x, y = p[0] + v * dt * math.cos(th), p[1] + v * dt * math.sin(th)
        return np.array([x, y, wrap_angle(p[2] + w * dt)])

    for i in range(scans):
        truth, odom = step(truth, v, w), step(odom, v * 1.02, w + 0.01)
        if truths is not None:
            truths.append(truth)
        scan = simulate_scan(world, compose(truth, laser), LDS01, rng, stamp=0.2 * i)
        est = loc.update(OdometryReading(odom.copy(), 0.2 * i), scan)
        err = math.inf if est.pose is None else float(np.hypot(*(est.pose[:2] - truth[:2])))
        out.append((est.status, err, est.reason))
    return out


def test_one_box_lets_the_laser_decide_as_the_robot_moves() -> None:
    out = _drive(boxes=1, scans=60)
    tracked = [i for i, (st, _, _) in enumerate(out) if st is Status.TRACKING]
    assert tracked, out[-1][2]
    first = tracked[0]
    assert "singled out by the laser" in out[first][2]
    assert all(out[i][0] is Status.AMBIGUOUS for i in range(first))
    assert max(out[i][1] for i in tracked) < 0.1


def test_when_the_camera_cannot_decide_the_laser_watches_as_without_keyframes() -> None:
    # keyframes exist but none is in view of any hypothesis: the camera is done, and the
    # laser watches the survivors as the robot moves, as with no keyframes at all
    out = _drive(boxes=1, scans=60, keyframes=_KeyframesOutOfView())
    tracked = [i for i, (st, _, _) in enumerate(out) if st is Status.TRACKING]
    assert tracked, out[-1][2]
    assert "no keyframe to compare them with in any direction: the laser watches" in out[0][2]
    assert "singled out by the laser" in out[tracked[0]][2]
    assert max(out[i][1] for i in tracked) < 0.1


def test_a_perfectly_symmetric_room_is_never_decided_without_keyframes() -> None:
    out = _drive(boxes=0, scans=60)
    assert not any(st is Status.TRACKING for st, _, _ in out)
    assert out[0][0] is Status.AMBIGUOUS
    assert "the laser watches them" in out[0][2]


def test_the_watch_says_when_moving_teaches_nothing() -> None:
    w = LaserWatch(np.array([COPY, TRUE]), np.zeros(3), slack=0.3, evidence=0.5)
    gate = FakeGate(0.95, 0.95)
    for i in range(2 * MIN_VIEWS):
        v = w.step(gate, SCAN, np.array([0.15 * (i + 1), 0.0, 0.0]))  # type: ignore[arg-type]
        assert (w.learning(v) == "") == (i + 1 < 2 * MIN_VIEWS)
    assert "fits as well" in w.learning(v)
    still = LaserWatch(np.array([COPY, TRUE]), np.zeros(3), slack=0.3, evidence=0.5)
    for _ in range(STILL_SCANS + 1):
        v = still.step(FakeGate(0.95, 0.5), SCAN, np.zeros(3))  # type: ignore[arg-type]
    assert "has not moved" in still.learning(v)


def _open_map(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every global search incomplete, as on a map whose free space meets unmapped space."""
    from symloc.localizer import decide_here

    real = decide_here.propose

    def incomplete(ctx: object, inp: object) -> decide_here.Hypotheses:
        hyp = real(ctx, inp)  # type: ignore[arg-type]
        return dataclasses.replace(hyp, complete=False, reason="an open map")

    monkeypatch.setattr(decide_here, "propose", incomplete)


def test_without_a_camera_the_leader_of_an_incomplete_search_is_earned_through_amcl(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # the truth may be none of the survivors: the one the watch singles out reseeds AMCL, and
    # nothing is published until AMCL's convergence earns it (here never: the room's 180-deg
    # copy stays AMCL's rival place, which only the watch's views had told apart)
    from symloc.localizer.decide_here import DecideHere

    _open_map(monkeypatch)
    truths: list[np.ndarray] = []
    seeded: list[tuple[int, np.ndarray]] = []
    real = DecideHere._reseed

    def record(self: DecideHere, ctx: object, inp: object, pose: np.ndarray, why: str) -> object:
        seeded.append((len(truths) - 1, np.asarray(pose, float).copy()))
        return real(self, ctx, inp, pose, why)  # type: ignore[arg-type]

    monkeypatch.setattr(DecideHere, "_reseed", record)
    out = _drive(boxes=1, scans=50, truths=truths)
    assert out[0][0] is Status.AMBIGUOUS, out[0][2]
    led = [i for i, (_, _, why) in enumerate(out) if "led the laser's watch" in why]
    assert led, out[-1][2]
    assert out[led[0]][0] is Status.LOST
    assert "AMCL reseeded there, pose to be earned" in out[led[0]][2]
    (at, pose), *_ = seeded
    assert at == led[0]
    assert np.hypot(*(pose[:2] - truths[at][:2])) < 0.1
    assert abs(wrap_angle(pose[2] - truths[at][2])) < math.radians(3.0)
    assert not any(st is Status.TRACKING for st, _, _ in out)
    assert not any("singled out by the laser" in why for _, _, why in out)


def test_without_a_camera_deciding_here_is_tried_again_soon(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # a perfectly symmetric room: each watch gives up; without keyframes the next is tried
    # decide_rest_no_camera scans later, not decide_rest
    _open_map(monkeypatch)
    out = _drive(boxes=0, scans=90)
    assert not any(st is Status.TRACKING for st, _, _ in out)
    starts = [
        i
        for i, (st, _, _) in enumerate(out)
        if st is Status.AMBIGUOUS and (i == 0 or out[i - 1][0] is not Status.AMBIGUOUS)
    ]
    assert len(starts) >= 2, [why for _, _, why in out]
    gave_up = next(i for i in range(starts[0], len(out)) if out[i][0] is not Status.AMBIGUOUS)
    assert starts[1] - gave_up <= LocalizerConfig().decide_rest_no_camera + 1
    assert LocalizerConfig().decide_rest_no_camera < LocalizerConfig().decide_rest
