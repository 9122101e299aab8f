"""What the localizer's phases share: its collaborators, one scan's inputs, the place visited.

:class:`Context` holds the collaborators every phase reads (the tracker, the place store, the
settings, the claim gate, the known places and the map's symmetries) and where the phases
write what callers read afterwards (:class:`Record`, the notes). :class:`Inputs` is one scan.
:class:`Visit` is the symmetric place being resolved, from the moment the pose becomes
ambiguous until it is decided or given up (Algorithm 2 and 3). The estimate builders at the end
are the only places an :class:`~symloc.localizer.types.Estimate` is made.
"""

from __future__ import annotations

import enum
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from symloc.geometry import compose, wrap_angle
from symloc.grid import OccupancyGrid
from symloc.symmetry.order import SymmetryOrder

from .centering import CentreFilter
from .claim import ClaimGate
from .config import LocalizerConfig
from .copies import PoseScorer, rotated_copies
from .map_symmetry import MapSymmetry
from .notes import Notes
from .rules import Streak
from .types import (
    Decision,
    Estimate,
    Hypothesis,
    KeyframeStore,
    Place,
    PlaceStore,
    PoseProposer,
    Request,
    Status,
    SymmetryVerdict,
    Tracker,
    TrackerResult,
    Verification,
)

__all__ = ["Context", "DecideCounts", "Inputs", "MappingRun", "Outcome", "Record", "Visit"]

FloatArray = NDArray[np.float64]


@dataclass
class DecideCounts:
    """What deciding from where the robot stands did (:mod:`symloc.localizer.decide_here`).

    ``entered`` times it started; ``proposals`` sets of hypotheses the laser proposed;
    ``laser_single`` times one hypothesis alone survived the laser; ``laser_claimed`` of those,
    poses the laser claimed at once (the others handed to AMCL to be earned);
    ``laser_seeded`` times one hypothesis survived a search that could not be complete (an
    open map, a list cut short) and, without a camera, AMCL was reseeded there to earn it;
    ``images`` images verified; ``verified`` images that verified one hypothesis with margin;
    ``rejected`` of those, poses the laser then refused; ``withheld`` poses the laser fitted
    but not precisely enough to claim at once (AMCL reseeded, the claim chain started there);
    ``claimed`` poses published at once;
    ``turns`` turns to look elsewhere; ``watched`` times the laser watched several hypotheses
    as the robot moved (no keyframes; :mod:`symloc.localizer.laser_watch`);
    ``gave_up`` times nothing was decided here;
    ``axis`` times the camera decided a corridor's heading class (status ``axis``).
    """

    entered: int = 0
    proposals: int = 0
    laser_single: int = 0
    laser_claimed: int = 0
    laser_seeded: int = 0
    images: int = 0
    verified: int = 0
    rejected: int = 0
    withheld: int = 0
    claimed: int = 0
    turns: int = 0
    watched: int = 0
    gave_up: int = 0
    axis: int = 0


@dataclass
class Record:
    """What the phases leave for callers (figures, the demo): the last visual decision that
    reseeded AMCL, AMCL's particles (N, 3) when the ambiguity was declared and just before
    a decision reseeded it, the camera's last check of the hypotheses deciding here (their
    map poses (K, 3) when the image was taken, and what the image said of each), and the
    counters of deciding here."""

    last_decision: tuple[Place, Decision] | None = None
    particles_at_ambiguity: FloatArray | None = None
    particles_before_decision: FloatArray | None = None
    last_camera_check: tuple[FloatArray, Verification] | None = None
    decide: DecideCounts = field(default_factory=DecideCounts)


@dataclass(frozen=True, eq=False)
class Context:
    """The localizer's collaborators, as every phase sees them.

    ``known_places`` is the localizer's own list (a mapped place is appended to it);
    ``gate`` None publishes the tracker's estimate unchecked (scripted tests only);
    ``proposer`` (the global scan-to-map search) and ``keyframes`` (the visual map's
    keyframes) serve deciding from where the robot stands (None: not available); ``grid`` the
    map, for where a corridor's axis runs on into unmapped space (None: the axis ends where
    the scan stops fitting, :mod:`symloc.localizer.axis_phase`).
    """

    tracker: Tracker
    places: PlaceStore
    config: LocalizerConfig
    gate: ClaimGate | None
    scorer: PoseScorer | None
    known_places: list[Place]
    map_symmetries: Sequence[MapSymmetry]
    notes: Notes
    record: Record
    proposer: PoseProposer | None = None
    keyframes: KeyframeStore | None = None
    grid: OccupancyGrid | None = None

    def note(self, text: str) -> None:
        """Log what happened (kept in the localizer's history)."""
        self.notes(text)

    def restart(self) -> None:
        """The localizer starts over: the claim gate forgets the claim's lifecycle."""
        if self.gate is not None:
            self.gate.restart()


@dataclass(frozen=True, eq=False)
class Inputs:
    """One scan: the tracker's ``result``, the judge's ``verdict``, the (deskewed) ``scan``,
    the ``image`` if one was requested, the odometry pose ``odom_pose`` (3,) and the odometry's
    ``turn_rate`` [rad/s] since the previous scan (the one the scan was deskewed with; 0 when
    unknown)."""

    result: TrackerResult
    verdict: SymmetryVerdict
    scan: object
    image: NDArray[np.uint8] | None
    odom_pose: FloatArray
    turn_rate: float = 0.0

    def centre_in_map(self) -> FloatArray:
        """The scan's symmetry centre (2,) in the map frame, seen from the tracker's estimate."""
        assert self.verdict.center is not None
        c = compose(
            self.result.estimate, np.array([self.verdict.center[0], self.verdict.center[1], 0.0])
        )
        return np.asarray(c[:2], dtype=np.float64)


@dataclass
class MappingRun:
    """Algorithm 5 step 11 under way: the images (and their map headings [rad]) taken so far."""

    images: list[NDArray[np.uint8]] = field(default_factory=list)
    headings: list[float] = field(default_factory=list)
    heading0: float | None = None


class Outcome(enum.Enum):
    """What one image at the centre gave (``.value`` as the notes spell it)."""

    NO_PLACE = "no_place"  # no stored place has this G-V distance
    REFUSED = "refused"
    NO_MATCH = "no_match"
    UNDETERMINED = "undetermined"


@dataclass
class Visit:
    """The symmetric place being resolved.

    ``order`` k (or a circle), ``gv`` its G-V distance [m] (re-estimated from every
    symmetric scan on the way), ``kind``, ``centre_map`` (2,) its centre in the map frame [m],
    ``centre`` the filter of its centre in the base frame, ``place`` the one known place it
    matches (for candidate poses from the scan), ``flips`` the non-symmetric verdicts on the
    way to the centre, ``attempt`` the image being tried of ``m`` directions, ``outcomes`` of
    the images tried, ``mapping`` when the place is being mapped.
    """

    order: SymmetryOrder
    gv: float
    kind: str
    centre_map: FloatArray
    centre: CentreFilter
    place: Place | None
    flips: Streak
    attempt: int = 0
    m: int = 0
    outcomes: list[Outcome] = field(default_factory=list)
    mapping: MappingRun | None = None


# --------------------------------------------------------------------------- estimates


def cov_from_std(xy_std: float, theta_std: float) -> FloatArray:
    """A diagonal pose covariance (3, 3) from a position std [m] and a heading std [rad]."""
    return np.diag([xy_std**2, xy_std**2, theta_std**2])


def reseed_tracker(ctx: Context, pose: FloatArray, cov: FloatArray) -> None:
    """AMCL reseeded at ``pose`` (3,) with ``cov`` (3, 3) widened to at least the reseed spread
    (``reseed_xy_std``, ``reseed_theta_std``): a decision's covariance can be tighter than the
    particle cloud should start."""
    cfg = ctx.config
    floor = cov_from_std(cfg.reseed_xy_std, cfg.reseed_theta_std)
    ctx.tracker.initialize_pose(pose, np.maximum(cov, floor))


def people(direction: int | None) -> str:
    """A direction index (0-based in the library) as people count it (1-based), for logs."""
    return "?" if direction is None else str(int(direction) + 1)


def lost(reason: str, result: TrackerResult) -> Estimate:
    """No pose worth reporting; AMCL's clusters for display."""
    return Estimate(status=Status.LOST, hypotheses=result.hypotheses, reason=reason)


def tracking(result: TrackerResult, reason: str) -> Estimate:
    """The tracker's estimate, unchecked (no claim gate)."""
    return Estimate(
        status=Status.TRACKING,
        pose=np.asarray(result.estimate, dtype=np.float64).copy(),
        covariance=np.asarray(result.covariance, dtype=np.float64).copy(),
        hypotheses=result.hypotheses,
        reason=reason,
    )


def ambiguous(
    inp: Inputs, visit: Visit, status: Status, request: Request | None, reason: str
) -> Estimate:
    """The pose known up to the visited place's symmetry: its ``k`` candidate poses."""
    return Estimate(
        status=status,
        hypotheses=candidates(inp, visit),
        order=visit.order,
        request=request,
        reason=reason,
    )


def candidates(inp: Inputs, visit: Visit) -> tuple[Hypothesis, ...]:
    """The ``k`` candidate poses.

    From the scan and the place when a known place of this order and G-V distance has a
    regular-polygon verdict with an ``axis``: the robot sees the centre at ``c`` and a corner
    middle along ``axis`` (base frame); direction ``j`` of the place looks from the centre
    at a corner middle along ``heading0 - j 2 pi / M``, so ``theta_j = heading0 - j 2 pi / M
    - axis`` and ``p_j = centre_map - R(theta_j) c``. Otherwise: AMCL's estimate rotated about
    the centre.
    """
    v = inp.verdict
    place = visit.place
    if (
        place is not None
        and v.symmetric
        and v.axis is not None
        and v.center is not None
        and place.m == visit.order.k
    ):
        j = np.arange(place.m)
        theta = wrap_angle(place.heading0 - j * 2.0 * np.pi / place.m - v.axis)
        c, s = np.cos(theta), np.sin(theta)
        x = place.center[0] - (c * v.center[0] - s * v.center[1])
        y = place.center[1] - (s * v.center[0] + c * v.center[1])
        poses = np.column_stack([x, y, theta])
        return tuple(Hypothesis(pose=p, weight=1.0 / place.m) for p in poses)
    copies = rotated_copies(inp.result.estimate, visit.centre_map, visit.order)
    w = 1.0 / len(copies)
    return tuple(Hypothesis(pose=p, weight=w) for p in copies)
