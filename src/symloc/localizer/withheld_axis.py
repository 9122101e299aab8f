"""A withheld claim whose heading is known: published as an axis estimate.

The claim gate withholds a tracked pose whose covariance is too long for the tolerance
(:mod:`symloc.localizer.claim`). Mostly it is long in one direction only: along a long
corridor, or radially far from a map's middle, where the map's scale error grows
(``ClaimConfig.map_scale_std``); across that direction and in heading the pose is as well known
as any claim. Publishing nothing then hides what the sensors did decide. So while the pose is
earned (AMCL converged past the copy check, the camera decided, or a claim was confirmed
since the operator's pose) and claims are not suspended, a withheld claim whose heading std
and across std pass the gate's bounds is reported with status ``axis``
(:class:`~symloc.localizer.types.AxisPose`): heading known, position known across its long
axis, somewhere on the segment of +-2 std along it. Nothing is claimed: it is not a pose
published as tracking, and the ROS node's ``map -> odom`` is as for any withheld claim.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .claim import Claim, ClaimGate, Verdict
from .types import AxisPose, Estimate, Hypothesis, Status

__all__ = ["ALONG_STDS", "withheld_axis"]

FloatArray = NDArray[np.float64]

#: The segment reaches this many standard deviations along the long axis either way.
ALONG_STDS = 2.0


def withheld_axis(gate: ClaimGate, claim: Claim | None, earned: bool) -> Estimate | None:
    """Status ``axis`` for ``claim`` when it was withheld for the length of its covariance
    alone, its heading and across std within the gate's bounds, the pose ``earned`` and claims
    not suspended; else None."""
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
    if float(np.sqrt(cov[2, 2])) > cfg.max_std_theta or float(minor) > cfg.max_std_xy:
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
