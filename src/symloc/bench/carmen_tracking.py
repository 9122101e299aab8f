"""The odometry ``symloc experiment amcl-carmen`` tracks with on a CARMEN log.

The corrected logs carry no raw odometry (their ``odom_*`` fields equal the corrected poses),
so the experiment corrupts the corrected trajectory with a differential drive's odometry noise
(:func:`noisy_odometry`), drawn from a stream of its own per log (:func:`tracking_stream`).
``symloc ros carmen-to-bag --odom-alpha`` writes the same odometry into a bag
(:func:`tracking_odometry`), so that a replay can be compared with the experiment on it.
"""

from __future__ import annotations

import zlib

import numpy as np
from numpy.typing import NDArray

from symloc.bench.shared_data import CARMEN_LOGS

__all__ = [
    "NOISE_WINDOW",
    "log_stream",
    "log_stream_index",
    "noise_windows",
    "noisy_odometry",
    "tracking_odometry",
    "tracking_stream",
]

FloatArray = NDArray[np.float64]


#: The motion [m], [rad] over which one draw of odometry noise is made: AMCL's default
#: ``update_min_d`` / ``update_min_a``, the motion its model integrates in one update.
NOISE_WINDOW = (0.25, 0.2)


def noise_windows(
    poses: FloatArray, window: tuple[float, float] = NOISE_WINDOW
) -> NDArray[np.intp]:
    """Pose indices ``(W + 1,)`` that cut the trajectory ``poses (T, 3)`` into windows of
    motion: from the first pose, a window ends at the first pose whose path from its start
    reaches ``window[0]`` [m] or whose turning (summed absolute heading changes) reaches
    ``window[1]`` [rad]; the last one ends at the last pose. A log that moves that much between
    scans has one increment per window."""
    from symloc.geometry import angle_diff

    step = np.hypot(*np.diff(poses[:, :2], axis=0).T)
    turn = np.abs(angle_diff(poses[1:, 2], poses[:-1, 2]))
    cuts = [0]
    path = rot = 0.0
    for i in range(step.size):  # sequential by nature (T scans, not particles)
        path += float(step[i])
        rot += float(turn[i])
        if path >= window[0] or rot >= window[1]:
            cuts.append(i + 1)
            path = rot = 0.0
    if cuts[-1] != step.size and step.size > 0:
        cuts.append(step.size)
    return np.asarray(cuts, dtype=np.intp)


def noisy_odometry(
    poses: FloatArray,
    alphas: tuple[float, float, float, float],
    rng: np.random.Generator,
    *,
    window: tuple[float, float] = NOISE_WINDOW,
) -> FloatArray:
    """Odometry poses ``(T, 3)`` from the true poses ``(T, 3)`` with rot-trans-rot noise.

    The noise is drawn per window of motion (:func:`noise_windows`, by default the motion of one
    AMCL update): the window's whole motion ``rot1, trans, rot2`` gets Gaussian noise of
    variance ``alpha1 rot^2 + alpha2 trans^2`` (rotations) and ``alpha3 trans^2 + alpha4 (rot1^2
    + rot2^2)`` (translation); the window's error is spread over its poses in proportion to the
    path (or, turning in place, the turning) up to each, and the windows are chained from the
    first pose. As in nav2's motion model, a rotation's noise uses ``min(|rot|, pi - |rot|)`` so
    that a backward step (``rot1`` near pi) is as noisy as a forward one.

    Why windows: the model's noise per metre must not depend on how often a log samples the
    pose. Drawn per scan, the 10 cm steps of freiburg-079, whose corrected direction of travel
    jitters (19 % of them start with a turn over 0.5 rad), gave AMCL's updates heading noise over
    twice its own model's in 17 % of them (0.2 % on the logs that move a metre per scan), and
    the experiment lost track there. A log that moves a window's worth between scans (csail,
    edmonton, orebro) gets the noise it got when it was drawn per scan, value for value: the
    draws are one per increment, and a window takes its last increment's.
    """
    from symloc.geometry import angle_diff, compose, relative
    from symloc.odometry import rot_trans_rot, rot_trans_rot_to_pose

    a1, a2, a3, a4 = alphas
    n = poses.shape[0] - 1
    e = rng.standard_normal((3, max(n, 0)))
    out = np.empty_like(poses)
    out[0] = poses[0]
    if n <= 0:
        return out
    cuts = noise_windows(poses, window)
    s_idx, e_idx = cuts[:-1], cuts[1:]
    r1, tr, r2 = rot_trans_rot(poses[s_idx], poses[e_idx])
    q1 = np.minimum(np.abs(r1), np.pi - np.abs(r1))
    q2 = np.minimum(np.abs(r2), np.pi - np.abs(r2))
    k = e_idx - 1  # each window's draw: its last increment's
    r1n = r1 + e[0, k] * np.sqrt(a1 * q1**2 + a2 * tr**2)
    trn = tr + e[1, k] * np.sqrt(a3 * tr**2 + a4 * (q1**2 + q2**2))
    r2n = r2 + e[2, k] * np.sqrt(a1 * q2**2 + a2 * tr**2)
    step = np.hypot(*np.diff(poses[:, :2], axis=0).T)
    turn = np.abs(angle_diff(poses[1:, 2], poses[:-1, 2]))
    zero = np.zeros(3)
    for w, (s, t) in enumerate(zip(s_idx, e_idx, strict=True)):
        truth_end = relative(poses[s], poses[t])
        noisy_end = rot_trans_rot_to_pose(zero, r1n[w], trn[w], r2n[w])
        err = noisy_end - truth_end
        err[2] = float(angle_diff(noisy_end[2], truth_end[2]))
        if t - s == 1:  # as drawn per increment, bit for bit
            out[t] = rot_trans_rot_to_pose(out[s], r1n[w], trn[w], r2n[w])
            continue
        path = np.cumsum(step[s:t])
        rot = np.cumsum(turn[s:t])
        frac = (
            path / path[-1]
            if path[-1] > 0.0
            else (rot / rot[-1] if rot[-1] > 0.0 else np.arange(1, t - s + 1) / (t - s))
        )
        for j, f in zip(range(s + 1, t + 1), frac, strict=True):
            out[j] = compose(out[s], relative(poses[s], poses[j]) + f * err)
    return out


#: The shared logs in the order that numbers their random streams. The first three are
#: :data:`CARMEN_LOGS`; the other five follow in the order the README's runs listed them.
STREAM_ORDER = (*CARMEN_LOGS, "orebro", "edmonton", "fhw", "csail", "acapulco")


def log_stream_index(name: str) -> int:
    """The number of log ``name``'s random streams: its place in :data:`STREAM_ORDER`, or for
    any other log ``len(STREAM_ORDER)`` plus the CRC-32 of its name. It depends on the name alone,
    never on which other logs are run or in what order."""
    if name in STREAM_ORDER:
        return STREAM_ORDER.index(name)
    return len(STREAM_ORDER) + zlib.crc32(name.encode())


#: The tasks of ``symloc experiment amcl-carmen`` that draw a random stream of their own per log.
STREAM_TASKS = ("tracking", "global")


def log_stream(name: str, seed: int, task: str) -> np.random.Generator:
    """The random stream of ``task`` (one of :data:`STREAM_TASKS`) on log ``name`` in ``symloc
    experiment amcl-carmen --seed seed``: independent per log and task
    (:func:`log_stream_index`), so one log's numbers do not depend on the others or on their
    order in ``--logs``, nor one task's on the other's."""
    if task not in STREAM_TASKS:
        raise ValueError(f"log_stream: task {task!r} is not one of {', '.join(STREAM_TASKS)}")
    return np.random.default_rng([seed, log_stream_index(name), STREAM_TASKS.index(task)])


def tracking_stream(name: str, seed: int) -> np.random.Generator:
    """The random stream of log ``name``'s tracking run (:func:`log_stream`, task
    ``"tracking"``)."""
    return log_stream(name, seed, "tracking")


def tracking_odometry(name: str, truth: FloatArray, alpha: float, seed: int) -> FloatArray:
    """The odometry poses (T, 3) [m, m, rad] the experiment's tracking feeds AMCL on log
    ``name`` run alone with ``--seed seed`` and ``--odom-alpha alpha``: the corrected poses
    ``truth`` (T, 3) with rot-trans-rot noise of variances ``alpha`` (:func:`noisy_odometry`),
    the first draw of :func:`tracking_stream`. ``symloc ros carmen-to-bag --odom-alpha`` writes
    these, so that a replay of the bag sees the experiment's own odometry."""
    return noisy_odometry(truth, (alpha,) * 4, tracking_stream(name, seed))
