"""A withheld claim whose heading is known: published as an axis estimate.

The claim gate withholds a tracked pose whose covariance is too long for the tolerance
(:mod:`symloc.localizer.claim`). Mostly it is long in one direction only: along a long
corridor, or radially far from a map's middle, where the map's scale error grows
(``ClaimConfig.map_scale_std``); across that direction and in heading the pose is as well known
as any claim. Publishing nothing then hides what the sensors did decide. So while the pose is
earned (AMCL converged past the copy check, the camera decided, or a claim was confirmed
since the operator's pose) and claims are not suspended, a withheld claim whose heading std
passes the gate's bound, and whose position across its long axis lies outside the tolerance
with no more chance than the gate accepts for a claim (:func:`across_outside_probability`),
is reported with status ``axis``
(:class:`~symloc.localizer.types.AxisPose`): heading known, position known across its long
axis, somewhere on the segment of +-2 std along it. Nothing is claimed: it is not a pose
published as tracking, and the ROS node's ``map -> odom`` is as for any withheld claim.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from .claim import Claim, ClaimGate, Verdict
from .types import AxisPose, Estimate, Hypothesis, Status

__all__ = ["ALONG_STDS", "across_outside_probability", "withheld_axis"]

FloatArray = NDArray[np.float64]

#: The segment reaches this many standard deviations along the long axis either way.
ALONG_STDS = 2.0


def across_outside_probability(minor: float, tolerance: float) -> float:
    """The chance that a position error of std ``minor`` [m] across the axis lies beyond
    ``tolerance`` [m] either way: the 1-D counterpart of
    :func:`~symloc.localizer.claim.outside_probability`.

    An axis report promises the position across the axis only, so it is held to the gate's
    chance (:attr:`~symloc.localizer.claim.ClaimConfig.max_outside_probability`) in that one
    direction: at four sigmas an across std of up to 2.79 cm for a 10 cm tolerance, where the
    2-D pose's circular bound (:attr:`~symloc.localizer.claim.ClaimConfig.max_std_xy`) is
    2.5 cm.
    """
    if minor <= 0.0:
        return 0.0
    return math.erfc(tolerance / (math.sqrt(2.0) * minor))


def withheld_axis(gate: ClaimGate, claim: Claim | None, earned: bool) -> Estimate | None:
    """Status ``axis`` for ``claim`` when it was withheld for the length of its covariance
    alone (its heading std within the gate's bound, its position across the long axis within
    the tolerance at the gate's chance), the pose ``earned`` and claims not suspended; else
    None."""
    if not earned or gate.suspended or claim is None or claim.verdict is not Verdict.WITHHELD:
        return None
    if claim.pose is None or claim.covariance is None or claim.match is None:
        return None
    cfg = gate.config
    if claim.match.inlier_fraction < cfg.min_claim_fit:
        return None  # withheld for a partial fit, not for precision
    cov = np.asarray(claim.covariance, dtype=np.float64)
    values, vectors = np.linalg.eigh(cov[:2, :2])
    minor, major = np.sqrt(np.maximum(values, 0.0))
    if float(np.sqrt(cov[2, 2])) > cfg.max_std_theta:
        return None
    across = across_outside_probability(float(minor), cfg.tolerance_position)
    if across > cfg.max_outside_probability:
        return None
    pose = np.asarray(claim.pose, dtype=np.float64)
    reach = ALONG_STDS * float(major) * vectors[:, 1]
    ends = np.stack([pose[:2] - reach, pose[:2] + reach])
    axis = AxisPose(pose=pose.copy(), covariance=cov.copy(), ends=ends)
    return Estimate(
        status=Status.AXIS,
        hypotheses=tuple(Hypothesis(pose=np.array([*e, pose[2]]), weight=0.5) for e in ends),
        reason=f"heading known, position along {2 * 100 * float(np.hypot(*reach)):.0f} cm "
        f"not: {claim.reason}",
        axis=axis,
    )
