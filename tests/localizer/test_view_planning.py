"""The view planner: the turn in place after which an image can verify the most hypotheses."""

from __future__ import annotations

import math

import numpy as np
import pytest

from symloc.localizer.view_planning import COUNT_CAP, plan_turn


def _along(heading: float, width: float = math.radians(40.0), count: int = 2):
    """Keyframes seen by every pose looking within ``width`` of ``heading``."""

    def counts(poses: np.ndarray) -> np.ndarray:
        off = np.abs((poses[:, 2] - heading + math.pi) % (2 * math.pi) - math.pi)
        return (off <= width).astype(np.int64) * count

    return counts


def test_turns_to_the_keyframes_heading() -> None:
    poses = np.array([[0.0, 0.0, 0.0]])
    plan = plan_turn(poses, _along(math.radians(120.0)))
    assert plan.useful
    assert plan.covered == 1
    assert abs(math.degrees(plan.turn) - 120.0) <= 40.0


def test_no_turn_when_here_is_as_good_as_anywhere() -> None:
    plan = plan_turn(np.array([[0.0, 0.0, 0.1]]), _along(0.0))
    assert plan.turn == 0.0
    assert plan.covered == 1


def test_prefers_the_heading_that_covers_more_hypotheses() -> None:
    # two hypotheses half a turn apart; keyframes along +x see only the first unless turned
    poses = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, math.pi]])

    def counts(p: np.ndarray) -> np.ndarray:
        off_x = np.abs((p[:, 2] + math.pi) % (2 * math.pi) - math.pi)
        near_first = (np.hypot(p[:, 0], p[:, 1]) < 0.5) & (off_x <= math.radians(40.0))
        # the second sees keyframes looking along +y only
        off_y = np.abs((p[:, 2] - math.pi / 2 + math.pi) % (2 * math.pi) - math.pi)
        near_second = (p[:, 0] > 0.5) & (off_y <= math.radians(40.0))
        first_too = (np.hypot(p[:, 0], p[:, 1]) < 0.5) & (
            np.abs((p[:, 2] + math.pi / 2 + math.pi) % (2 * math.pi) - math.pi)
            <= math.radians(40.0)
        )
        return (near_first | near_second | first_too).astype(np.int64)

    plan = plan_turn(poses, counts)
    # a turn near -pi/2 shows the first hypothesis -y keyframes and the second +y ones;
    # the smallest such turn wins
    assert plan.covered == 2
    assert abs(plan.turn + math.pi / 2) <= math.radians(40.0)
    assert plan.turn == pytest.approx(math.radians(-60.0))


def test_seen_headings_are_skipped() -> None:
    poses = np.array([[0.0, 0.0, 0.0]])
    plan = plan_turn(poses, _along(0.0, width=math.pi), seen=[0.0], spacing=math.radians(45.0))
    assert abs(plan.turn) > math.radians(45.0)
    # every heading seen: nothing left to plan
    seen = [math.radians(a) for a in range(-180, 180, 30)]
    assert not plan_turn(poses, _along(0.0, width=math.pi), seen=seen).useful


def test_no_keyframes_anywhere_is_not_useful() -> None:
    plan = plan_turn(np.array([[0.0, 0.0, 0.0]]), lambda p: np.zeros(len(p), np.int64))
    assert not plan.useful
    assert plan.covered == 0


def test_counts_are_capped_per_hypothesis() -> None:
    poses = np.array([[0.0, 0.0, 0.0]])
    plan = plan_turn(poses, _along(0.0, count=50))
    assert plan.expected == COUNT_CAP


def test_a_turn_lands_where_a_short_stop_still_covers_the_hypothesis() -> None:
    # keyframes seen looking within 40 deg of -95 deg: turns from -135 to -55 deg cover the
    # hypothesis. The smallest, -60, is at the edge: a turn that stops 10 deg short (at -50)
    # sees nothing and must turn again; with the margin the plan sends it to -90
    poses = np.array([[0.0, 0.0, 0.0]])
    counts = _along(math.radians(-95.0))
    plain = plan_turn(poses, counts)
    assert plain.covered == 1
    assert plain.turn == pytest.approx(math.radians(-60.0))
    robust = plan_turn(poses, counts, margin=math.radians(10.0))
    assert robust.covered == 1
    assert robust.turn == pytest.approx(math.radians(-90.0))
    for stop in (robust.turn - math.radians(10.0), robust.turn + math.radians(10.0)):
        assert counts(poses + np.array([0.0, 0.0, stop]))[0] > 0
