"""Telling nearly symmetric copies apart with the laser alone, as the robot moves.

In a room that is symmetric but for a piece of furniture, one scan often leaves two poses: the
truth and its rotated copy, which explains a few percent fewer beams (the furniture is small or
half hidden). One scan is not enough to tell them apart with the margins the localizer keeps
(:attr:`~symloc.localizer.config.LocalizerConfig.decide_laser_margin`, the copy check's ratio
and map slack, which allow for map errors and people). Without keyframes the camera cannot
choose either. But the copy's deficit comes back at every new view: the furniture is where the
truth's map has it, not where the copy's has it.

:class:`LaserWatch` carries the hypotheses by odometry from scan to scan, aligns each to the map
with the claim gate's matcher and, at every new view (the robot moved :data:`VIEW_STEP` or
turned :data:`VIEW_TURN` since the last one), records the share of beams each explains
(within the match's inlier distance) and, with a map slack, the share within that slack of the
walls (a map error's size: :mod:`symloc.localizer.copies`). A rival is ruled out when, summed
over the views, its deficit against the leader (the hypothesis with the most beams explained in
total) minus :data:`VIEW_ALLOWANCE` per view reaches ``evidence``, for the tight share and the
loose one alike, after at least :data:`MIN_VIEWS` views. The allowance keeps a bias of a
percent per view (a map rasterised a little unevenly, a person in one copy's view) from adding
up to a decision: in a perfectly symmetric room nothing is ever decided. One scan's worth of
evidence is the single-scan rule's margin (``decide_laser_margin``, 0.15 of the beams);
``evidence`` asks several of those, from different places.

The watch is given up (:meth:`LaserWatch.learning`) when moving teaches nothing: after
``2 * MIN_VIEWS`` views no rival is behind the leader by more than the allowance (the copies of
a perfectly symmetric room fit alike: the paper's drive to the centre must have its turn), or
the robot has not moved to a new view for :data:`STILL_SCANS` scans.

The caller (:class:`~symloc.localizer.decide_here.DecideHere`) then lets the laser confirm the
leader (:meth:`~symloc.localizer.claim.ClaimGate.confirm`) and starts tracking there, as after a
visual decision: the choice among the copies is made, so the copy check is not asked again.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from symloc.geometry import angle_diff, compose, relative, wrap_angle
from symloc.scan import LaserScan

from .claim import ClaimGate

__all__ = [
    "MIN_VIEWS",
    "STILL_SCANS",
    "VIEW_ALLOWANCE",
    "VIEW_STEP",
    "VIEW_TURN",
    "LaserWatch",
    "WatchVerdict",
]

FloatArray = NDArray[np.float64]

#: A new view: the robot moved this far [m] since the last view ...
VIEW_STEP = 0.1
#: ... or turned this much [rad].
VIEW_TURN = math.radians(8.0)
#: Views before anything is decided.
MIN_VIEWS = 4
#: Share of beams per view a rival's deficit must exceed to count as evidence.
VIEW_ALLOWANCE = 0.01
#: Scans in a row without a new view (the robot standing) before the watch is given up.
STILL_SCANS = 25


@dataclass(frozen=True, slots=True)
class WatchVerdict:
    """Where the watch stands after a scan: ``leader`` the index of the hypothesis with the
    most beams explained over the views (None before the first view), ``decided`` True when
    every rival is ruled out, ``evidence`` the least evidence [share of beams] against a
    rival (tight and loose alike), ``views`` the views so far."""

    leader: int | None
    decided: bool
    evidence: float
    views: int


@dataclass
class LaserWatch:
    """The hypotheses ``poses`` (K, 3) watched as the robot moves (see the module docstring).

    ``odom`` the odometry pose (3,) the poses refer to; ``slack`` [m] the copy check's map
    slack (0: the tight share alone); ``evidence`` the summed deficit [share of beams] that
    rules a rival out. ``tight`` and ``loose`` (views, K) hold each view's shares.
    """

    poses: FloatArray
    odom: FloatArray
    slack: float
    evidence: float
    last_view: FloatArray | None = None
    #: the share of beams each hypothesis explains at the last scan (K,)
    last_fits: FloatArray = field(default_factory=lambda: np.zeros(0))
    tight: list[FloatArray] = field(default_factory=list)
    loose: list[FloatArray] = field(default_factory=list)
    #: scans since the last new view
    still: int = 0

    @property
    def views(self) -> int:
        """Views recorded so far."""
        return len(self.tight)

    def _new_view(self, odom: FloatArray) -> bool:
        last = self.last_view
        if last is None:
            return True
        moved = float(np.hypot(*(odom[:2] - last[:2])))
        turned = abs(float(angle_diff(odom[2], last[2])))
        return moved >= VIEW_STEP or turned >= VIEW_TURN

    def step(self, gate: ClaimGate, scan: LaserScan, odom_pose: FloatArray) -> WatchVerdict:
        """Carry the hypotheses to ``odom_pose`` (3,), align them to ``scan`` and, at a new
        view, record how well each explains it."""
        odom = np.asarray(odom_pose, dtype=np.float64)
        moved = relative(self.odom, odom)
        carried = np.asarray(compose(self.poses, moved), dtype=np.float64).reshape(-1, 3)
        carried[:, 2] = wrap_angle(carried[:, 2])
        self.odom = odom.copy()
        view = self._new_view(odom)
        tight = np.empty(carried.shape[0])
        loose = np.empty(carried.shape[0])
        for i in range(carried.shape[0]):
            pose, fit = gate.fit(carried[i], scan)
            carried[i], tight[i] = pose, fit
            if view and self.slack > 0.0:
                loose[i] = gate.share_within(pose, scan, self.slack)
        self.poses = carried
        self.last_fits = tight
        self.still = 0 if view else self.still + 1
        if view:
            self.last_view = odom.copy()
            self.tight.append(tight)
            if self.slack > 0.0:
                self.loose.append(loose)
        return self.verdict()

    def verdict(self) -> WatchVerdict:
        """The leader and the evidence against its rivals so far."""
        if not self.tight:
            return WatchVerdict(None, False, 0.0, 0)
        tight = np.array(self.tight)
        n = tight.shape[0]
        leader = int(np.argmax(tight.sum(axis=0)))
        if tight.shape[1] < 2:
            return WatchVerdict(leader, n >= MIN_VIEWS, math.inf, n)
        least = self._least(tight, leader)
        if self.loose:
            least = min(least, self._least(np.array(self.loose), leader))
        return WatchVerdict(leader, n >= MIN_VIEWS and least >= self.evidence, least, n)

    def learning(self, verdict: WatchVerdict) -> str:
        """ "" while the watch may still decide; else why moving teaches nothing (see the
        module docstring)."""
        if self.still >= STILL_SCANS:
            return f"the robot has not moved to a new view for {self.still} scans"
        if verdict.views >= 2 * MIN_VIEWS and verdict.evidence <= 0.0:
            return f"after {verdict.views} views every rival still fits as well as the leader"
        return ""

    @staticmethod
    def _least(shares: FloatArray, leader: int) -> float:
        """The least summed deficit (less the allowance per view) of a rival against
        ``leader`` over the views ``shares`` (views, K)."""
        deficit = shares[:, [leader]] - shares - VIEW_ALLOWANCE
        sums = deficit.sum(axis=0)
        sums[leader] = math.inf
        return float(sums.min())
