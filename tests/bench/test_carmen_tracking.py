"""The experiment's odometry noise (symloc.bench.carmen_tracking): drawn per window of motion,
so its size per metre does not depend on how often a log samples the pose."""

from __future__ import annotations

import numpy as np
import pytest

from symloc.bench.carmen_tracking import (
    STREAM_ORDER,
    log_stream,
    log_stream_index,
    noise_windows,
    noisy_odometry,
    tracking_stream,
)
from symloc.odometry import rot_trans_rot, rot_trans_rot_to_pose

ALPHAS = (0.01, 0.01, 0.01, 0.01)


def _per_increment(poses: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """The draw per increment (the experiment's before windows), written out."""
    r1, tr, r2 = rot_trans_rot(poses[:-1], poses[1:])
    e = rng.standard_normal((3, r1.size))
    q1 = np.minimum(np.abs(r1), np.pi - np.abs(r1))
    q2 = np.minimum(np.abs(r2), np.pi - np.abs(r2))
    r1n = r1 + e[0] * np.sqrt(0.01 * q1**2 + 0.01 * tr**2)
    trn = tr + e[1] * np.sqrt(0.01 * tr**2 + 0.01 * (q1**2 + q2**2))
    r2n = r2 + e[2] * np.sqrt(0.01 * q2**2 + 0.01 * tr**2)
    out = np.empty_like(poses)
    out[0] = poses[0]
    for i in range(r1.size):
        out[i + 1] = rot_trans_rot_to_pose(out[i], r1n[i], trn[i], r2n[i])
    return out


def _line(step: float, jitter: float = 0.0) -> np.ndarray:
    """A 10 m straight drive sampled every ``step`` m, its positions off the line by
    +-``jitter`` m in turn (a corrected trajectory's direction of travel jitters)."""
    x = np.arange(0.0, 10.0 + 1e-9, step)
    y = jitter * (-1.0) ** np.arange(x.size)
    y[0] = y[-1] = 0.0
    return np.column_stack([x, y, np.zeros(x.size)])


def test_a_log_that_moves_a_window_per_scan_gets_the_per_increment_draw_bit_for_bit() -> None:
    poses = _line(0.5)
    poses[:, 2] = np.linspace(0.0, 1.0, poses.shape[0])
    assert np.array_equal(noise_windows(poses), np.arange(poses.shape[0]))
    got = noisy_odometry(poses, ALPHAS, np.random.default_rng(3))
    assert np.array_equal(got, _per_increment(poses, np.random.default_rng(3)))


def test_windows_gather_small_steps_and_end_at_the_last_pose() -> None:
    poses = _line(0.1)
    cuts = noise_windows(poses)
    assert cuts[0] == 0
    assert cuts[-1] == poses.shape[0] - 1
    assert set(np.diff(cuts[:-1])) == {3}  # 0.3 m >= 0.25 m: three 10 cm steps a window


def test_the_noise_per_metre_does_not_depend_on_the_sampling() -> None:
    """The end heading's spread over many draws is about the same sampled every 50 cm or every
    5 cm with 1 cm of jitter; drawn per increment it was more than twice as large."""

    def spread(poses: np.ndarray, window: tuple[float, float]) -> float:
        ends = [
            noisy_odometry(poses, ALPHAS, np.random.default_rng(s), window=window)[-1, 2]
            for s in range(300)
        ]
        return float(np.std(ends))

    coarse = spread(_line(0.5), (0.25, 0.2))
    fine = spread(_line(0.05, 0.01), (0.25, 0.2))
    per_scan = spread(_line(0.05, 0.01), (0.0, 0.0))
    assert 0.5 < fine / coarse < 2.0
    assert per_scan > 2.0 * coarse


def test_a_logs_streams_depend_on_its_name_alone() -> None:
    """Before, a log outside the first three was numbered by its place in ``--logs``, so
    ``--logs orebro fhw`` and ``--logs fhw orebro`` drew different starts for the same log."""
    # the README's runs listed the five other logs in this order: their numbers are kept
    assert [log_stream_index(n) for n in STREAM_ORDER] == list(range(len(STREAM_ORDER)))
    assert log_stream_index("seattle") == log_stream_index("seattle")
    assert log_stream_index("seattle") >= len(STREAM_ORDER)
    assert log_stream_index("seattle") != log_stream_index("mit-killian")
    a = tracking_stream("fhw", 1).standard_normal(4)
    b = tracking_stream("fhw", 1).standard_normal(4)
    c = tracking_stream("csail", 1).standard_normal(4)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, c)


def test_each_task_of_a_log_draws_its_own_stream_and_the_runs_numbers_are_kept() -> None:
    """The global starts and the tracking of one log draw different streams, each the
    ``[seed, log number, task number]`` stream the results in docs/results were drawn from
    (tracking 0, global 1); an unknown task is refused by name."""
    g = log_stream("aces", 2, "global").standard_normal(3)
    t = log_stream("aces", 2, "tracking").standard_normal(3)
    assert not np.array_equal(g, t)
    assert np.array_equal(g, np.random.default_rng([2, 1, 1]).standard_normal(3))
    assert np.array_equal(t, tracking_stream("aces", 2).standard_normal(3))
    with pytest.raises(ValueError, match="'kidnap'"):
        log_stream("aces", 2, "kidnap")
