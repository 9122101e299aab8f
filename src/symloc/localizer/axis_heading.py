"""The camera tells a corridor's two headings apart.

An axis family (:mod:`symloc.localizer.axis`) leaves two heading classes, ``theta`` and
``theta + pi``, each a line of hypotheses. One image is checked against the keyframes every
hypothesis predicts (:meth:`~symloc.localizer.types.KeyframeStore.verify`). Several
hypotheses of the right class usually verify (neighbours along the corridor expect the same
keyframes, and the camera hardly measures where along the corridor it stands), so no single
hypothesis is verified with margin; what must be unique here is the heading class:

- the winning class holds a verified hypothesis with at least ``min_inliers`` inliers (one
  weak match never decides);
- its best verified inliers are at least the store's ``margin`` times the best *rival* fit of
  the other class: any of its fits, verified or not, except one whose measured camera heading
  agrees with the winner's (within the store's ``heading_tolerance``) on a keyframe that a
  verified hypothesis of the winner should be seeing too, which is evidence for the winner
  (as :func:`~symloc.localizer.vision_store.single_verified` counts rivals).

The winner's camera heading (its best verified hypothesis' heading plus the measured offset)
agrees with the laser's heading of the class within the tolerance, since verified means so.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from symloc.geometry import wrap_angle

from .types import Verification
from .verified_together import same_view

__all__ = ["HeadingVote", "vote_heading"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


@dataclass(frozen=True)
class HeadingVote:
    """The image's answer: ``winner`` the heading class (0 or 1) it decides, None when it
    does not; ``best`` (2,) each class' best verified inliers (0: none verified); ``rival``
    the best rival fit against the leading class; ``heading`` [rad] the camera's heading
    measured by the leader's best verified hypothesis (NaN when none verified); ``reason``
    in words."""

    winner: int | None
    best: tuple[int, int]
    rival: int
    heading: float
    reason: str


def vote_heading(
    poses: FloatArray, classes: IntArray, verification: Verification, min_inliers: int
) -> HeadingVote:
    """Which heading class the image decides (see the module docstring).

    ``poses`` (K, 3) the hypotheses shown, ``classes`` (K,) their heading class (0 or 1),
    ``verification`` the store's answer for them (its ``checks``, ``margin`` and
    ``heading_tolerance`` are needed; a store that gives none decides nothing)."""
    p = np.asarray(poses, dtype=np.float64).reshape(-1, 3)
    cls = np.asarray(classes, dtype=np.int64).reshape(-1)
    checks = verification.checks
    margin, tol = verification.margin, verification.heading_tolerance
    if len(checks) != p.shape[0] or cls.shape[0] != p.shape[0]:
        return HeadingVote(None, (0, 0), 0, math.nan, "the keyframe store gave no check per pose")
    if not (math.isfinite(margin) and math.isfinite(tol)):
        return HeadingVote(None, (0, 0), 0, math.nan, "the keyframe store gave no margin")
    inliers = np.array([c.inliers for c in checks], dtype=np.int64)
    verified = np.array([c.verified for c in checks], dtype=bool)
    offsets = np.array([c.heading_offset for c in checks], dtype=np.float64)
    best = [int(inliers[verified & (cls == c)].max(initial=0)) for c in (0, 1)]
    if max(best) == 0:
        counts = ", ".join(f"{k} {v}" for k, v in verification.counts.items())
        return HeadingVote(None, (0, 0), 0, math.nan, f"no hypothesis verified ({counts})")
    lead = int(np.argmax(best))
    mine = np.flatnonzero(verified & (cls == lead))
    k = int(mine[np.argmax(inliers[mine])])
    heading = float(wrap_angle(p[k, 2] + offsets[k]))
    measured = np.asarray(wrap_angle(p[:, 2] + offsets - heading), dtype=np.float64)
    seen = [checks[j].expected for j in mine]
    here = np.array([same_view(c.keyframe, seen) for c in checks], dtype=bool)
    agrees = np.isfinite(offsets) & (np.abs(np.nan_to_num(measured, nan=math.pi)) <= tol) & here
    rivals = (cls != lead) & ~agrees
    rival = int(inliers[rivals].max(initial=0))
    share = (best[0], best[1])
    which = f"heading class {lead + 1} ({math.degrees(p[k, 2]):.0f} deg)"
    if best[lead] < min_inliers:
        why = f"{which} verified with only {best[lead]} inliers ({min_inliers} needed)"
        return HeadingVote(None, share, rival, heading, why)
    if best[lead] < margin * rival:
        why = (
            f"{which} verified with {best[lead]} inliers, but the half-turned class fits with "
            f"{rival} (margin {margin:g}x not met)"
        )
        return HeadingVote(None, share, rival, heading, why)
    why = (
        f"{which} verified: {best[lead]} inliers against at most {rival} for the half-turned "
        f"class; camera heading {math.degrees(heading):.1f} deg"
    )
    return HeadingVote(lead, share, rival, heading, why)
