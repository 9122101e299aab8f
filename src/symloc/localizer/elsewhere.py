"""Places elsewhere: the evidence the claim gate needs before it gives a tracked pose up.

A scan that contradicts the tracked pose does not show the robot was carried off: clutter,
people or a part of the building the map got wrong make a scan fit nowhere, and a scan of a
stretch of wall fits many places of a large map. So the claim gate
(:class:`symloc.localizer.claim.ClaimGate`) asks the global scan-to-map search where the
scan fits, keeps the places that explain it clearly better than the tracked pose
(:func:`places_explaining`), and follows them by odometry over the next scans
(:meth:`Places.followed`): a robot carried off stays where it was put, and its place explains
every scan; a look-alike stops explaining them as the robot moves. Only then is the pose given
up.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from symloc.geometry import compose, relative, wrap_angle
from symloc.scan import LaserScan

from .types import Proposal

__all__ = ["Places", "nearest_within", "places_explaining"]

FloatArray = NDArray[np.float64]

#: Aligns a scan to the map from a pose (3,): the aligned pose (3,) and the share of its
#: returning beams that then fit (:meth:`symloc.localizer.claim.ClaimGate.fit`).
Align = Callable[[FloatArray, LaserScan], tuple[FloatArray, float]]


@dataclass(frozen=True)
class Places:
    """Places ``poses`` (K, 3) [m, m, rad] that explained a scan while the tracked pose did
    not, at odometry pose ``odom`` (3,), followed for ``scans`` scans over ``path`` [m] and
    ``turned`` [rad] (summed heading changes) since; ``complete`` when the search that found
    them listed every place that explains that scan."""

    poses: FloatArray
    odom: FloatArray
    scans: int = 0
    path: float = 0.0
    turned: float = 0.0
    complete: bool = True

    def followed(
        self, odom: FloatArray, scan: LaserScan, align: Align, min_fit: float
    ) -> Places | None:
        """The places carried by odometry to ``odom`` (3,) and aligned to ``scan``: those
        whose aligned share of fitting beams is at least ``min_fit``; None when none is."""
        step = relative(self.odom, odom)
        kept = []
        for pose in self.poses:
            aligned, share = align(compose(pose, step), scan)
            if share >= min_fit:
                kept.append(aligned)
        if not kept:
            return None
        return dataclasses.replace(
            self,
            poses=np.array(kept, dtype=np.float64),
            odom=np.asarray(odom, dtype=np.float64).copy(),
            scans=self.scans + 1,
            path=self.path + math.hypot(step[0], step[1]),
            turned=self.turned + abs(float(wrap_angle(step[2]))),
        )

    def moved(self, motion: tuple[float, float]) -> bool:
        """True once the robot went ``motion[0]`` [m] or turned ``motion[1]`` [rad]."""
        return self.path >= motion[0] or self.turned >= motion[1]


def places_explaining(proposal: Proposal, need: float) -> FloatArray:
    """The poses (K, 3) of ``proposal`` whose share of explained end points is at least
    ``need``."""
    return np.asarray(proposal.poses[proposal.scores >= need], dtype=np.float64).reshape(-1, 3)


def nearest_within(poses: FloatArray, pose: FloatArray, window: tuple[float, float]) -> int | None:
    """Index of the first of ``poses`` (K, 3) within ``window`` (metres, radians) of
    ``pose`` (3,) in position and heading; None when none is."""
    off = poses[:, :2] - pose[:2]
    turn = np.abs(wrap_angle(poses[:, 2] - pose[2]))
    near = np.flatnonzero((np.hypot(off[:, 0], off[:, 1]) <= window[0]) & (turn <= window[1]))
    return int(near[0]) if near.size else None
