"""The odometry ``symloc experiment amcl-carmen`` tracks with on a CARMEN log.

The corrected logs carry no raw odometry (their ``odom_*`` fields equal the corrected poses),
so the experiment corrupts the corrected trajectory with a differential drive's odometry noise
(:func:`noisy_odometry`), drawn from a stream of its own per log (:func:`tracking_stream`).
``symloc ros carmen-to-bag --odom-alpha`` writes the same odometry into a bag
(:func:`tracking_odometry`), so that a replay can be compared with the experiment on it.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from symloc.bench.shared_data import CARMEN_LOGS

__all__ = ["noisy_odometry", "tracking_odometry", "tracking_stream"]

FloatArray = NDArray[np.float64]


def noisy_odometry(
    poses: FloatArray, alphas: tuple[float, float, float, float], rng: np.random.Generator
) -> FloatArray:
    """Odometry poses ``(T, 3)`` from the true poses ``(T, 3)`` with rot-trans-rot noise.

    Each increment's ``rot1, trans, rot2`` gets Gaussian noise of variance
    ``alpha1 rot^2 + alpha2 trans^2`` (rotations) and ``alpha3 trans^2 + alpha4 (rot1^2 +
    rot2^2)`` (translation), and the noisy increments are chained from the first pose. As in
    nav2's motion model, a rotation's noise uses ``min(|rot|, pi - |rot|)`` so that a backward
    step (``rot1`` near pi) is as noisy as a forward one.
    """
    from symloc.odometry import rot_trans_rot, rot_trans_rot_to_pose

    a1, a2, a3, a4 = alphas
    r1, tr, r2 = rot_trans_rot(poses[:-1], poses[1:])
    n = r1.size
    e = rng.standard_normal((3, n))
    q1 = np.minimum(np.abs(r1), np.pi - np.abs(r1))
    q2 = np.minimum(np.abs(r2), np.pi - np.abs(r2))
    r1n = r1 + e[0] * np.sqrt(a1 * q1**2 + a2 * tr**2)
    trn = tr + e[1] * np.sqrt(a3 * tr**2 + a4 * (q1**2 + q2**2))
    r2n = r2 + e[2] * np.sqrt(a1 * q2**2 + a2 * tr**2)
    out = np.empty_like(poses)
    out[0] = poses[0]
    for i in range(n):  # chaining is sequential by nature (T scans, not particles)
        out[i + 1] = rot_trans_rot_to_pose(out[i], r1n[i], trn[i], r2n[i])
    return out


def tracking_stream(name: str, seed: int, position: int = 0) -> np.random.Generator:
    """The random stream of log ``name``'s tracking run in ``symloc experiment amcl-carmen
    --seed seed``: independent per log and task, so one log's numbers do not depend on the
    others. A log outside :data:`CARMEN_LOGS` is numbered after them by its ``position`` in
    ``--logs`` (0 when it is run alone)."""
    idx = CARMEN_LOGS.index(name) if name in CARMEN_LOGS else len(CARMEN_LOGS) + position
    return np.random.default_rng([seed, idx, 0])


def tracking_odometry(name: str, truth: FloatArray, alpha: float, seed: int) -> FloatArray:
    """The odometry poses (T, 3) [m, m, rad] the experiment's tracking feeds AMCL on log
    ``name`` run alone with ``--seed seed`` and ``--odom-alpha alpha``: the corrected poses
    ``truth`` (T, 3) with rot-trans-rot noise of variances ``alpha`` (:func:`noisy_odometry`),
    the first draw of :func:`tracking_stream`. ``symloc ros carmen-to-bag --odom-alpha`` writes
    these, so that a replay of the bag sees the experiment's own odometry."""
    return noisy_odometry(truth, (alpha,) * 4, tracking_stream(name, seed))
