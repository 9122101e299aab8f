"""Typed outputs of the localizer and the small Protocols its collaborators satisfy.

The :class:`~symloc.localizer.localizer.Localizer` is passive: every call returns an
:class:`Estimate` whose ``status`` says how far the pose can be trusted, and an optional
:class:`Request` that whoever drives the robot carries out (go to the centre, face a direction,
capture an image, rotate). The collaborators (AMCL, the symmetry judgement, the visual map) are
described here as ``typing.Protocol`` s so the state machine can be tested with scripted
stand-ins and run with the real parts through the adapters in
:mod:`symloc.localizer.adapters`.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from symloc.errors import ConfigurationError
from symloc.hypothesis import Hypothesis
from symloc.symmetry.order import SymmetryOrder
from symloc.vision.place import Place

__all__ = [
    "AxisPose",
    "Decision",
    "DecisionStatus",
    "Estimate",
    "Hypothesis",
    "HypothesisVerdict",
    "KeyframeStore",
    "Place",
    "PlaceStore",
    "PoseProposer",
    "Proposal",
    "Request",
    "RequestKind",
    "Status",
    "SymmetryJudge",
    "SymmetryVerdict",
    "Tracker",
    "TrackerResult",
    "Verification",
]

FloatArray = NDArray[np.float64]


class Status(enum.Enum):
    """How far a caller can trust an :class:`Estimate`.

    ``TRACKING``: the pose is earned (AMCL converged where the map is not symmetric, or after a
    visual decision). ``AMBIGUOUS``: the pose is known only up to a symmetry of order ``k``; the
    ``k`` candidate poses are listed. ``GOING_TO_CENTRE``: ambiguous, and the robot has been asked
    to drive to the place's centre (Algorithm 2). ``DECIDING``: at the centre, images are being
    compared with the visual map (Algorithm 3). ``LOST``: no pose worth reporting. ``AXIS``: the
    heading is known (the camera told the two headings of a corridor apart) but not the position
    along the corridor's axis: :attr:`Estimate.axis` says where on which segment; nothing is
    claimed (:mod:`symloc.localizer.axis_phase`).
    """

    TRACKING = "tracking"
    AMBIGUOUS = "ambiguous"
    GOING_TO_CENTRE = "going_to_centre"
    DECIDING = "deciding"
    LOST = "lost"
    AXIS = "axis"


class RequestKind(enum.Enum):
    """What the localizer asks the driver to do next.

    ``GO_TO_CENTRE`` is Algorithm 2's drive to a symmetric place's centre (slow, to stop within
    millimetres); ``GO_TO`` a drive at travelling speed to where the map is precise enough for a
    claim the gate withholds (:func:`symloc.localizer.phases.precision_request`): the claim is
    published from the first scan that passes on the way; also deciding here's drive towards a
    round room's centre (``LocalizerConfig.decide_round_reach``)."""

    GO_TO_CENTRE = "go_to_centre"
    GO_TO = "go_to"
    FACE_DIRECTION = "face_direction"
    CAPTURE_IMAGE = "capture_image"
    ROTATE = "rotate"


@dataclass(frozen=True, slots=True)
class Request:
    """A request to the driver, expressed in the robot's own (base) frame.

    Attributes
    ----------
    kind : RequestKind
    target : ndarray of shape (2,) or None
        For ``GO_TO_CENTRE``: the centre in the base frame [m], re-estimated from every scan.
        For ``GO_TO``: the place to drive to in the base frame [m], re-computed at every scan.
    angle : float or None
        For ``FACE_DIRECTION``: the bearing to face in the base frame [rad] (turn by this much).
        For ``ROTATE``: the rotation still to do [rad], counter-clockwise positive (the visual
        search turns clockwise, so it is negative).
    """

    kind: RequestKind
    target: FloatArray | None = None
    angle: float | None = None

    def __post_init__(self) -> None:
        if self.kind in (RequestKind.GO_TO_CENTRE, RequestKind.GO_TO):
            if self.target is None:
                raise ConfigurationError(f"Request.target: {self.kind.name} needs a (2,) target")
            t = np.array(self.target, dtype=np.float64)
            if t.shape != (2,) or not np.all(np.isfinite(t)):
                raise ConfigurationError(
                    f"Request.target: expected a finite (2,) point, got {self.target!r}"
                )
            t.setflags(write=False)
            object.__setattr__(self, "target", t)
        if self.kind in (RequestKind.FACE_DIRECTION, RequestKind.ROTATE):
            if self.angle is None or not np.isfinite(self.angle):
                raise ConfigurationError(
                    f"Request.angle: {self.kind.value} needs a finite angle, got {self.angle!r}"
                )
            object.__setattr__(self, "angle", float(self.angle))


@dataclass(frozen=True, slots=True)
class AxisPose:
    """Heading known, position along an axis not (status ``axis``).

    Attributes
    ----------
    pose : ndarray of shape (3,)
        The middle of the segment, with the decided heading (x [m], y [m], theta [rad]; map
        frame). Not a claim: the robot is somewhere on the segment.
    covariance : ndarray of shape (3, 3)
        Long along the axis (std about length / sqrt(12), so that the whole segment lies inside
        the 95 % ellipsoid), tight across it and in heading.
    ends : ndarray of shape (2, 2)
        The segment's end points [m] (map frame).
    open_ends : int
        How many of the ends were lengthened into space the map does not cover (the passage
        may go on there; 0: both ends are where the scan stops fitting the map).
    """

    pose: FloatArray
    covariance: FloatArray
    ends: FloatArray
    open_ends: int = 0

    def __post_init__(self) -> None:
        for name, shape in (("pose", (3,)), ("covariance", (3, 3)), ("ends", (2, 2))):
            value = np.array(getattr(self, name), dtype=np.float64)
            if value.shape != shape or not np.all(np.isfinite(value)):
                raise ConfigurationError(
                    f"AxisPose.{name}: expected a finite array of shape {shape}, got "
                    f"{getattr(self, name)!r}"
                )
            value.setflags(write=False)
            object.__setattr__(self, name, value)

    @property
    def length(self) -> float:
        """The segment's length [m]."""
        return float(np.hypot(*(self.ends[1] - self.ends[0])))


@dataclass(frozen=True, slots=True)
class Estimate:
    """One output of the localizer.

    Attributes
    ----------
    status : Status
    pose : ndarray of shape (3,) or None
        Set only when ``status`` is ``TRACKING``: a pose the localizer has earned.
    covariance : ndarray of shape (3, 3) or None
        The covariance of ``pose`` (x, y, theta) when ``pose`` is set.
    hypotheses : tuple of Hypothesis
        When ambiguous: the ``order`` candidate poses related by the place's rotation.
        When tracking: the AMCL clusters (for display).
    order : SymmetryOrder or None
        The symmetry order ``k`` when ambiguous (:data:`SymmetryOrder.CIRCLE` for a circle);
        ``None`` otherwise.
    request : Request or None
        What the driver should do next; ``None`` means carry on.
    reason : str
        One line saying why the status is what it is (for logs and users).
    axis : AxisPose or None
        Set exactly when ``status`` is ``AXIS``: the heading and the segment the robot stands
        on. ``pose`` stays None then: only an earned pose is ever a pose.
    """

    status: Status
    pose: FloatArray | None = None
    covariance: FloatArray | None = None
    hypotheses: tuple[Hypothesis, ...] = ()
    order: SymmetryOrder | None = None
    request: Request | None = None
    reason: str = ""
    axis: AxisPose | None = None

    def __post_init__(self) -> None:
        if self.order is not None and not isinstance(self.order, SymmetryOrder):
            raise ConfigurationError(
                f"Estimate.order: expected a SymmetryOrder or None, got {self.order!r}"
            )
        if self.status is Status.TRACKING:
            if self.pose is None or self.covariance is None:
                raise ConfigurationError("Estimate: status tracking needs a pose and a covariance")
        elif self.pose is not None:
            raise ConfigurationError(
                f"Estimate.pose: only a tracking estimate carries a pose, not {self.status.value}"
            )
        if (self.status is Status.AXIS) != (self.axis is not None):
            raise ConfigurationError(
                "Estimate.axis: set exactly when the status is axis "
                f"(status {self.status.value}, axis {'set' if self.axis is not None else 'None'})"
            )


# --------------------------------------------------------------------------- collaborators


@dataclass(frozen=True, slots=True)
class TrackerResult:
    """What the localizer needs from one AMCL update.

    ``estimate`` (3,), ``covariance`` (3, 3) of the heaviest cluster, ``hypotheses`` (every
    cluster, heaviest first, each with its own covariance), ``particles`` (N, 3) and ``weights``
    (N,) for display.
    ``confident`` the tracker's own verdict (:mod:`symloc.mcl.confidence`, the project's one
    definition); None (a tracker that gives none) counts as not converged.
    """

    estimate: FloatArray
    covariance: FloatArray
    hypotheses: tuple[Hypothesis, ...]
    particles: FloatArray | None = None
    weights: FloatArray | None = None
    updated: bool = True
    confident: bool | None = None


@runtime_checkable
class Tracker(Protocol):
    """The laser tracker (AMCL) as the localizer uses it."""

    def initialize_global(self) -> None:
        """Spread the particles over the free space."""

    def initialize_pose(self, pose: FloatArray, covariance: FloatArray) -> None:
        """Reseed the particles around ``pose`` (3,) with ``covariance`` (3, 3)."""

    def update(self, odom: object, scan: object) -> TrackerResult:
        """One filter step with an odometry reading and a scan."""

    def force_update(self) -> None:
        """Integrate the next scan even if the robot has not moved (nav2's
        ``request_nomotion_update``)."""


@dataclass(frozen=True, slots=True)
class SymmetryVerdict:
    """The part of a symmetry report the localizer uses.

    ``order`` k (:data:`SymmetryOrder.CIRCLE` for a circle; None when the scan allows no
    verdict, too little range or field of view); ``center`` (2,) and ``corners`` (K, 2) are in
    the sensor (base) frame [m]; ``facing`` is the bearing [rad] in the base frame of the middle
    between two adjacent corners (None when there are no corners); ``axis`` [rad] is the
    direction in the base frame from the centre to one such corner middle (regular polygons
    only), from which the ``k`` candidate poses follow given the place's map pose.
    """

    symmetric: bool
    order: SymmetryOrder | None
    kind: str
    center: FloatArray | None
    gv_distance: float
    facing: float | None = None
    corners: FloatArray | None = None
    reason: str = ""
    axis: float | None = None

    def __post_init__(self) -> None:
        if self.order is not None and not isinstance(self.order, SymmetryOrder):
            raise ConfigurationError(
                f"SymmetryVerdict.order: expected a SymmetryOrder or None, got {self.order!r}"
            )
        if self.symmetric and self.order is None:
            raise ConfigurationError("SymmetryVerdict: a symmetric verdict needs an order")


class SymmetryJudge(Protocol):
    """Algorithm 1: judge one scan."""

    def __call__(self, scan: object) -> SymmetryVerdict: ...


class DecisionStatus(enum.Enum):
    """The outcome of one visual decision (``.value`` as logs and JSON spell it)."""

    DECIDED = "decided"
    UNDETERMINED = "undetermined"  # no clear winner: try another direction
    NO_MATCH = "no_match"  # the image resembles none of the place's images
    REFUSED = "refused"  # too few features: the image cannot decide anything


@dataclass(frozen=True, slots=True)
class Decision:
    """The outcome of comparing one query image with one place's stored images.

    ``status`` is a :class:`DecisionStatus` (its value is accepted too: ``"decided"``,
    ``"undetermined"``, ``"no_match"``, ``"refused"``). ``direction`` is the stored image
    index, ``offset`` [rad] the query's heading minus that image's heading (CCW positive).
    ``heading`` [rad], when given, is the decided map heading (the stored image's own heading
    plus the offset); otherwise the localizer uses ``heading0 - direction * 2 pi / m + offset``.
    """

    status: DecisionStatus
    direction: int | None = None
    offset: float = 0.0
    score: float = 0.0
    reason: str = ""
    heading: float | None = None

    def __post_init__(self) -> None:
        try:
            status = DecisionStatus(self.status)
        except ValueError as err:
            raise ConfigurationError(
                f"Decision.status: expected one of {[s.value for s in DecisionStatus]}, "
                f"got {self.status!r}"
            ) from err
        object.__setattr__(self, "status", status)


class PlaceStore(Protocol):
    """The visual map with its G-V index, as the localizer uses it."""

    def candidates(self, gv_distance: float, order: SymmetryOrder) -> Sequence[Place]:
        """Places whose G-V distance matches within the index's tolerance."""

    def decide(self, place: Place, image: NDArray[np.uint8]) -> Decision:
        """Decide the direction of ``image`` against ``place``'s stored images."""

    def all_places(self) -> Sequence[Place]:
        """Every stored place (the localizer's known places at start-up)."""

    def add_place(
        self,
        center: FloatArray,
        heading0: float,
        order: SymmetryOrder,
        gv_distance: float,
        kind: str,
        images: Sequence[NDArray[np.uint8]],
        headings: Sequence[float] | None = None,
    ) -> Place:
        """Store a new place with its ``m`` images taken clockwise from ``heading0``.

        ``headings`` (m,) [rad], when given, are the measured map headings of the images
        (a turn by odometry is never exactly 360/m); the localizer always gives them.
        """


# --------------------------------------------------------------------------- deciding here


@dataclass(frozen=True, slots=True)
class Proposal:
    """Poses that explain one scan, from a single scan and the map alone.

    ``poses`` (K, 3) robot poses in the map frame, best first; ``scores`` (K,) the share of
    the scan's end points each explains; ``complete`` False when the list may miss poses that
    explain the scan as well (a budget stopped the search, or more poses fit than are listed:
    a corridor); ``reason`` why (empty when complete).
    """

    poses: FloatArray
    scores: FloatArray
    complete: bool
    reason: str = ""


class PoseProposer(Protocol):
    """The laser's proposals from one scan (the global scan-to-map search,
    :class:`symloc.localizer.adapters.GlobalSearchProposer`)."""

    def propose(self, scan: object) -> Proposal:
        """Every distinct pose of the map that explains ``scan``, best first."""


@dataclass(frozen=True, slots=True)
class HypothesisVerdict:
    """What one image says about one hypothesis: ``status`` ``"verified"``,
    ``"contradicted"`` or ``"unknown"``; ``inliers`` of its best geometric fit (0 without
    one); ``heading_offset`` [rad] the camera's heading measured by that fit minus the
    hypothesis' heading (NaN without a fit); ``keyframe`` the id of the keyframe of that fit
    (None: no fit, or the store does not say) and ``expected`` the ids of the keyframes the
    hypothesis should be seeing (empty: none, or the store does not say)."""

    status: str
    inliers: int
    heading_offset: float = math.nan
    keyframe: int | None = None
    expected: tuple[int, ...] = ()

    @property
    def verified(self) -> bool:
        """True when the image verifies the hypothesis."""
        return self.status == "verified"


@dataclass(frozen=True, slots=True)
class Verification:
    """What one image says about several pose hypotheses.

    ``index`` is the single hypothesis the image verifies with margin (None: none);
    ``pose`` (3,) that hypothesis with the camera's heading (None without a decision);
    ``reason`` in words; ``counts`` how many hypotheses were verified, contradicted, unknown.
    ``checks`` one :class:`HypothesisVerdict` per hypothesis in the order given (empty: the
    store does not say), with the store's ``margin`` (how many times a rival's inliers the
    winner needs) and ``heading_tolerance`` [rad] (NaN: not given); deciding a corridor's
    heading class needs all three (:mod:`symloc.localizer.axis_heading`).
    ``refined_heading`` [rad] and ``heading_std`` [rad]: ``pose``'s heading measured again by
    planar motion (:mod:`symloc.vision.heading_refinement`) and its standard deviation; NaN:
    not measured (``pose`` has the verification's coarse heading, which the localizer trusts
    to ``decide_theta_std``).
    """

    index: int | None
    pose: FloatArray | None
    reason: str
    counts: Mapping[str, int] = field(default_factory=dict)
    checks: tuple[HypothesisVerdict, ...] = ()
    margin: float = math.nan
    heading_tolerance: float = math.nan
    refined_heading: float = math.nan
    heading_std: float = math.nan


@runtime_checkable
class KeyframeStore(Protocol):
    """The visual map's keyframes (map pose, ORB features, BoW vector), as the localizer
    uses them: hypotheses verified by one image (:mod:`symloc.vision.verification`)."""

    def keyframe_count(self) -> int:
        """How many keyframes the visual map holds (0: the camera cannot decide here)."""

    def expected_counts(self, poses: FloatArray, reach: float = 0.0) -> NDArray[np.int64]:
        """How many keyframes a camera at each pose of ``poses`` (P, 3) (map frame) should be
        seeing, (P,): 0 where an image there cannot verify anything (view planning).
        ``reach`` [m]: each pose stands for the poses up to this far from it (hypotheses
        sampled along a line), so its keyframes may lie that much further away."""

    def verify(
        self,
        poses: FloatArray,
        image: NDArray[np.uint8],
        reach: float = 0.0,
        *,
        refine: bool = False,
        round_centre: FloatArray | None = None,
    ) -> Verification:
        """Check each hypothesis of ``poses`` (K, 3) (map frame, at the moment ``image`` was
        taken) against the keyframes it predicts the camera sees; name the single one verified
        with margin, or none. ``reach`` [m] as in :meth:`expected_counts`. ``refine``: also
        measure the verified one's heading again (:attr:`Verification.refined_heading`; about
        a second of CPU, so only where the laser cannot set the heading), on a round map
        with its position turning about ``round_centre`` (2,) [m] with the heading."""
