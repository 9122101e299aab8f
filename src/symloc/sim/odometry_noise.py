"""Noisy odometry from a reference trajectory (Thrun et al. 2005, Table 5.6, sample_motion_model).

Each increment between consecutive reference poses is decomposed into ``rot1, trans, rot2``
(:func:`symloc.odometry.rot_trans_rot`); zero-mean Gaussian noise with variances

- ``rot1, rot2``: ``alpha1 * rot^2 + alpha2 * trans^2``
- ``trans``: ``alpha3 * trans^2 + alpha4 * (rot1^2 + rot2^2)``

is added (the model and parameter names of nav2_amcl's ``DifferentialMotionModel``; like it,
the rotations that enter the variances are taken modulo a half turn, so that driving backwards
does not count as two half turns). Increments shorter than ``in_place_below`` [m] count as
turns on the spot in the variances (``rot1 = 0``, the whole turn in ``rot2``): the corrected
CARMEN poses move the laser a few centimetres sideways while the robot turns, which would
otherwise give a meaningless direction of travel ``rot1`` of up to 180 degrees. The noisy
increments are then chained from the first reference pose (the motion itself is unchanged).

The default ``alpha1..alpha4 = (0.04, 0.01, 0.01, 0.04)`` are GMapping's default odometry error
parameters (``stt = 0.2, str = 0.1, srr = 0.1, srt = 0.2``, standard deviations per unit
motion) squared into the variance coefficients of this model.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc._checks import as_rng, check_array, check_positive
from symloc.geometry import angle_diff
from symloc.odometry import rot_trans_rot, rot_trans_rot_to_pose

__all__ = ["DEFAULT_ALPHAS", "noisy_odometry"]

#: alpha1..alpha4 used for the CARMEN experiments (rad^2/rad^2, rad^2/m^2, m^2/m^2, m^2/rad^2).
DEFAULT_ALPHAS = (0.04, 0.01, 0.01, 0.04)


def noisy_odometry(
    reference: ArrayLike,
    alphas: tuple[float, float, float, float] = DEFAULT_ALPHAS,
    rng: np.random.Generator | int | None = None,
    *,
    in_place_below: float = 0.1,
) -> NDArray[np.float64]:
    """Odometry poses ``(N, 3)`` made by perturbing the increments of ``reference`` (N, 3).

    The first pose equals ``reference[0]``; ``alphas`` are the four odometry noise
    parameters (all >= 0). Deterministic for a given ``rng`` seed.
    """
    ref = check_array(reference, "reference", shape=(None, 3))
    for k, a in enumerate(alphas):
        check_positive(a, f"alphas[{k}]", allow_zero=True)
    if len(alphas) != 4:
        raise ValueError("alphas: expected 4 values alpha1..alpha4")
    gen = as_rng(rng)
    a1, a2, a3, a4 = (float(a) for a in alphas)
    r1, tr, r2 = rot_trans_rot(ref[:-1], ref[1:])
    n = r1.shape[0]
    spot = tr < in_place_below
    v1 = np.where(spot, 0.0, r1)
    v2 = np.where(spot, angle_diff(ref[1:, 2], ref[:-1, 2]), r2)
    q1 = np.minimum(np.abs(v1), np.pi - np.abs(v1))
    q2 = np.minimum(np.abs(v2), np.pi - np.abs(v2))
    sd_r1 = np.sqrt(a1 * q1**2 + a2 * tr**2)
    sd_tr = np.sqrt(a3 * tr**2 + a4 * (q1**2 + q2**2))
    sd_r2 = np.sqrt(a1 * q2**2 + a2 * tr**2)
    nr1 = r1 + gen.normal(size=n) * sd_r1
    ntr = tr + gen.normal(size=n) * sd_tr
    nr2 = r2 + gen.normal(size=n) * sd_r2
    out = np.empty_like(ref)
    out[0] = ref[0]
    for i in range(n):  # a chain: each pose depends on the previous one
        out[i + 1] = rot_trans_rot_to_pose(out[i], nr1[i], ntr[i], nr2[i])
    return out
