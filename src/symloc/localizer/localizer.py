"""The symloc localizer: Algorithm 5 of the paper as a passive state machine.

Feed it odometry, scans and (when it asked for one) an image with :meth:`Localizer.update`; it
returns an :class:`~symloc.localizer.types.Estimate` every time. AMCL tracks by default. When the
scan is judged symmetric (Algorithm 1) and the pose has not been earned, or AMCL's hypotheses
split into clusters related by the place's rotation, the heading is no longer trusted: the
localizer reports ``ambiguous`` with the ``k`` candidate poses and asks the driver to go to the
centre and face the middle between two adjacent corners (Algorithm 2), captures an image, looks
the place up by G-V distance, decides the direction against the visual map (Algorithm 3),
turning clockwise by 360/M between attempts, and reseeds AMCL at the decided pose. When no
place matches it maps the place (Algorithm 5 step 11) if allowed and says so. It never returns a
pose it has not earned: ``Estimate.pose`` is set only with status ``tracking``.

Earned means one of: AMCL converged to one tight cluster while the scan was not symmetric and
no rotated copy of the estimate about a known symmetric place explains the scan as well; or a
visual decision. After :meth:`Localizer.reset_global` (start-up or kidnapping) nothing is earned.
"""

from __future__ import annotations

import enum
import inspect
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from symloc._checks import check_in_range, check_positive
from symloc.errors import ConfigurationError
from symloc.geometry import angle_diff, compose, inverse, wrap_angle
from symloc.mcl.motion_model import carry_by_odometry
from symloc.odometry import OdometryReading, twist_between
from symloc.scan import LaserScan, deskew, sensor_twist

from .centering import CentreFilter
from .claim import Claim, ClaimGate
from .directions import directions_for
from .types import (
    Decision,
    Estimate,
    Hypothesis,
    Place,
    PlaceStore,
    Request,
    RequestKind,
    Status,
    SymmetryJudge,
    SymmetryVerdict,
    Tracker,
    TrackerResult,
)

__all__ = ["Localizer", "LocalizerConfig", "rotated_copies", "symmetry_consistent"]

FloatArray = NDArray[np.float64]
#: The operator's pose (3,), its covariance (3, 3) and the odometry pose (3,) it refers to.
_OperatorPose = tuple[FloatArray, FloatArray, FloatArray | None]
#: Poses x scan -> (K,) scores in [0, 1]: how well the scan fits the map at each pose.
PoseScorer = Callable[[FloatArray, Any], FloatArray]

#: How many candidates to list for a circle (infinite order).
CIRCLE_SAMPLES = 8


@dataclass(frozen=True, slots=True)
class LocalizerConfig:
    """Settings of the localizer (units: m, rad, counts).

    Attributes
    ----------
    min_cluster_weight : a cluster is a hypothesis when its weight is at least this.
    converged_weight : the heaviest cluster's weight for AMCL to count as converged.
    converged_xy_std, converged_theta_std : its largest position std [m] and heading std [rad].
    converged_updates : consecutive converged updates before the pose is earned.
    symmetry_position_tol, symmetry_angle_tol : how close a cluster must be to a rotated copy of
        the heaviest one to count as its symmetric image [m], [rad].
    copy_score_ratio : with a pose scorer, a rotated copy whose score is at least this fraction
        of the estimate's own score explains the scan as well (the ambiguity is real).
    place_radius_factor : a known place covers the disc of radius factor x its G-V distance.
    centre_smoothing : weight of a new per-scan centre estimate (:class:`CentreFilter`).
    centre_tolerance : the robot has reached the centre when the scan's centre is this close [m].
    facing_tolerance : facing done when the bearing to the corner-middle is below this [rad].
    rotate_tolerance : a ROTATE request is done when odometry turned within this [rad].
    flip_patience : consecutive non-symmetric verdicts before the trip to the centre is dropped.
    max_centering_updates : updates allowed for going to the centre and facing.
    relocalize_after : consecutive filter updates, while lost, at which the scan contradicts
        AMCL's estimate before AMCL is spread over the whole map again (a kidnapped robot's
        particles may all be in the wrong place, and nav2's filter has no recovery by default).
    allow_mapping : build a visual map for a place that matches nothing (Algorithm 5 step 11).
    reseed_xy_std, reseed_theta_std : smallest spread of the AMCL reseed after a decision.
    decision_xy_std, decision_theta_std : how well a visual decision knows the pose before the
        laser sets it (the stored centre's and the decided heading's std) [m], [rad].
    """

    min_cluster_weight: float = 0.05
    converged_weight: float = 0.9
    converged_xy_std: float = 0.15
    converged_theta_std: float = math.radians(8.0)
    converged_updates: int = 3
    symmetry_position_tol: float = 0.35
    symmetry_angle_tol: float = math.radians(15.0)
    copy_score_ratio: float = 0.9
    place_radius_factor: float = 1.2
    centre_tolerance: float = 0.01
    facing_tolerance: float = math.radians(1.5)
    rotate_tolerance: float = math.radians(3.0)
    flip_patience: int = 5
    max_centering_updates: int = 600
    relocalize_after: int = 100
    allow_mapping: bool = False
    reseed_xy_std: float = 0.03
    reseed_theta_std: float = math.radians(2.0)
    decision_xy_std: float = 0.15
    decision_theta_std: float = math.radians(2.0)
    centre_smoothing: float = 0.5

    def __post_init__(self) -> None:
        for name in (
            "converged_xy_std",
            "converged_theta_std",
            "symmetry_position_tol",
            "symmetry_angle_tol",
            "place_radius_factor",
            "centre_tolerance",
            "facing_tolerance",
            "rotate_tolerance",
            "reseed_xy_std",
            "reseed_theta_std",
            "decision_xy_std",
            "decision_theta_std",
        ):
            check_positive(getattr(self, name), f"LocalizerConfig.{name}")
        check_in_range(self.min_cluster_weight, "LocalizerConfig.min_cluster_weight", 0.0, 1.0)
        check_in_range(self.converged_weight, "LocalizerConfig.converged_weight", 0.0, 1.0)
        check_in_range(self.centre_smoothing, "LocalizerConfig.centre_smoothing", 1e-6, 1.0)
        check_in_range(self.copy_score_ratio, "LocalizerConfig.copy_score_ratio", 0.0, 1.0)
        for name in (
            "converged_updates",
            "flip_patience",
            "max_centering_updates",
            "relocalize_after",
        ):
            value = getattr(self, name)
            if not isinstance(value, int) or isinstance(value, bool) or value < 1:
                raise ConfigurationError(
                    f"LocalizerConfig.{name}: expected an integer >= 1, got {value!r}"
                )


class _Phase(enum.Enum):
    LOST = "lost"
    TRACKING = "tracking"
    CENTERING = "centering"
    FACING = "facing"
    CAPTURE = "capture"
    ROTATING = "rotating"
    SETTLED = "settled"  # ambiguous, nothing more to try here


def rotated_copies(pose: FloatArray, center: FloatArray, order: int) -> FloatArray:
    """The ``k`` poses ``(k, 3)`` obtained by rotating ``pose`` (3,) about ``center`` (2,).

    ``order`` 0 (a circle) gives :data:`CIRCLE_SAMPLES` evenly spaced copies. Copy 0 is ``pose``.
    """
    k = CIRCLE_SAMPLES if order == 0 else int(order)
    if k < 1:
        raise ConfigurationError(f"rotated_copies: order must be >= 0, got {order}")
    phi = 2.0 * np.pi * np.arange(k) / k
    c, s = np.cos(phi), np.sin(phi)
    d = np.asarray(pose[:2], dtype=np.float64) - center
    out = np.empty((k, 3))
    out[:, 0] = center[0] + c * d[0] - s * d[1]
    out[:, 1] = center[1] + s * d[0] + c * d[1]
    out[:, 2] = wrap_angle(pose[2] + phi)
    return out


def symmetry_consistent(
    hypotheses: Sequence[Hypothesis],
    center: FloatArray,
    order: int,
    *,
    min_weight: float,
    position_tol: float,
    angle_tol: float,
) -> int:
    """How many well-weighted clusters are symmetric images of the heaviest one.

    Counts the heaviest cluster itself, so a value >= 2 means AMCL's hypotheses are related by
    the place's rotation of order ``order`` (0: a circle, any angle) about ``center`` (2,) [m].
    """
    strong = [h for h in hypotheses if h.weight >= min_weight]
    if not strong:
        return 0
    ref = max(strong, key=lambda h: h.weight)
    count = 1
    for h in strong:
        if h is ref:
            continue
        phi = float(angle_diff(h.pose[2], ref.pose[2]))
        if order > 0:
            step = 2.0 * np.pi / order
            phi = round(phi / step) * step
            if abs(float(angle_diff(h.pose[2], ref.pose[2] + phi))) > angle_tol:
                continue
        if abs(phi) < angle_tol:
            continue  # the same heading: a split of one cluster, not a symmetric copy
        expect = rotated_copies(ref.pose, center, 0 if order == 0 else order)
        if order == 0:
            expect = rotated_copies(ref.pose, center, 1).copy()
            c, s = math.cos(phi), math.sin(phi)
            d = ref.pose[:2] - center
            expect[0, :2] = center + np.array([c * d[0] - s * d[1], s * d[0] + c * d[1]])
            expect[0, 2] = wrap_angle(ref.pose[2] + phi)
        dist = np.hypot(expect[:, 0] - h.pose[0], expect[:, 1] - h.pose[1])
        if float(dist.min()) <= position_tol:
            count += 1
    return count


def _order_people(order: int) -> str:
    """A symmetry order as people read it: ``inf`` for a circle (order 0 in the library)."""
    return "inf" if int(order) == 0 else str(int(order))


def _people(direction: int | None) -> str:
    """A direction index (0-based in the library) as people count it (1-based), for logs."""
    return "?" if direction is None else str(int(direction) + 1)


def _cov(xy_std: float, theta_std: float) -> FloatArray:
    return np.diag([xy_std**2, xy_std**2, theta_std**2])


class Localizer:
    """Algorithm 5 over a stream of odometry, scans and images.

    Parameters
    ----------
    tracker : Tracker
        AMCL (or any tracker with ``initialize_global``, ``initialize_pose``, ``update``).
    judge : SymmetryJudge
        Algorithm 1 on one scan.
    places : PlaceStore
        The visual map with its G-V index.
    config : LocalizerConfig, optional
    scorer : callable, optional
        ``scorer(poses (K, 3), scan) -> (K,)`` scores in [0, 1] of the scan against the map; used
        to test whether rotated copies of AMCL's estimate about a known place explain the scan as
        well as the estimate (the ambiguity is real even when AMCL has collapsed to one copy).
    known_places : sequence of Place, optional
        Symmetric places of the map (from the mapping stage) for that test.
    claim_gate : ClaimGate, optional
        Carries the tracker's estimate to every scan and confirms it with the laser before
        it is published (:mod:`symloc.localizer.claim`). Without one, the tracker's estimate
        is published unchecked: only scripted tests do that.
    map_symmetries : sequence of MapSymmetry, optional
        Rotational symmetries of the whole map (``centre``, ``order``;
        :func:`~symloc.localizer.map_symmetry.map_symmetries`). Where AMCL converged outside any
        known place, a rotated copy that explains the scan as well keeps the pose unearned
        (status ambiguous, the copies as candidates).
    laser_pose : (3,) array, optional
        Where the laser sits on the robot (``base_from_laser``: x [m], y [m], yaw [rad]; a
        scan of a laser mounted upside down is mirrored first, :func:`symloc.scan.mirror`).
        The localizer uses it to undo the sensor's own motion during a sweep (a laser off the
        centre also moves sideways while the robot turns); the tracker, the judge, the scorer
        and the claim gate are given the same pose when they are built
        (:func:`symloc.ros.assemble.make_localizer`). Default: at the robot's origin, looking
        along +x.
    """

    def __init__(
        self,
        tracker: Tracker,
        judge: SymmetryJudge,
        places: PlaceStore,
        config: LocalizerConfig | None = None,
        *,
        scorer: PoseScorer | None = None,
        known_places: Sequence[Place] = (),
        map_symmetries: Sequence[Any] = (),
        claim_gate: ClaimGate | None = None,
        laser_pose: FloatArray | Sequence[float] = (0.0, 0.0, 0.0),
    ) -> None:
        lp = np.asarray(laser_pose, dtype=np.float64).reshape(-1)
        if lp.shape != (3,) or not np.all(np.isfinite(lp)):
            raise ConfigurationError(
                f"Localizer.laser_pose: expected finite (x, y, yaw), got {lp.tolist()}"
            )
        #: the laser in the robot frame (``base_from_laser``), see the class docstring
        self.laser_pose = lp
        self.tracker = tracker
        self.judge = judge
        self.places = places
        self.config = config if config is not None else LocalizerConfig()
        self.scorer = scorer
        self.known_places = list(known_places)
        #: rotational symmetries of the map itself (:func:`~symloc.localizer.map_symmetry.
        #: map_symmetries`): a converged pose whose rotated copy fits the scan as well is not
        #: earned.
        self.map_symmetries = list(map_symmetries)
        #: every pose published as tracking passes this gate (:mod:`symloc.localizer.claim`);
        #: None publishes the tracker's estimate unchecked (scripted tests only)
        self.claim_gate = claim_gate
        self.log: list[str] = []
        self._last_result: TrackerResult | None = None
        self._last_verdict: SymmetryVerdict | None = None
        #: (place, decision) of the last visual decision that reseeded AMCL.
        self.last_decision: tuple[Place, Decision] | None = None
        #: AMCL's particles when the ambiguity was declared (for figures).
        self.particles_at_ambiguity: FloatArray | None = None
        #: AMCL's particles just before the visual decision reseeded it (for figures).
        self.particles_before_decision: FloatArray | None = None
        self._last_odom: OdometryReading | None = None
        self._operator_pose: _OperatorPose | None = None
        self._reset_state()
        self._phase = _Phase.LOST

    # ------------------------------------------------------------------ public

    @property
    def _phase(self) -> _Phase:
        return self._phase_value

    @_phase.setter
    def _phase(self, value: _Phase) -> None:
        # a confirmed pose vouches for the next one only while tracking lasts
        if value is not _Phase.TRACKING and self.claim_gate is not None:
            self.claim_gate.forget_chain()
        self._phase_value = value

    @property
    def phase(self) -> str:
        """The internal phase name (finer than the status; for logs and tests)."""
        return self._phase.value

    def reset_global(self) -> None:
        """Forget the pose (start-up or kidnapping): global AMCL, nothing earned."""
        self.tracker.initialize_global()
        self._reset_state()
        self._phase = _Phase.LOST
        self._note("reset: global initialisation, pose not earned")

    def set_pose(self, pose: FloatArray, covariance: FloatArray) -> None:
        """A pose given by the operator (like RViz's 2D Pose Estimate): reseed and earn it."""
        self.tracker.initialize_pose(np.asarray(pose, float), np.asarray(covariance, float))
        if self.claim_gate is not None:
            self.claim_gate.reset()
        self._reset_state()
        self._phase = _Phase.TRACKING
        # the operator chose among any symmetric copies (the laser still confirms the pose);
        # the odometry pose it refers to is the next update's
        self._operator_pose = (
            np.asarray(pose, dtype=np.float64).copy(),
            np.asarray(covariance, dtype=np.float64).copy(),
            None,
        )
        self._note("pose set by the operator")

    def update(
        self, odom: OdometryReading, scan: object, image: NDArray[np.uint8] | None = None
    ) -> Estimate:
        """One step: odometry reading, laser scan and, if one was requested, an image.

        ``odom`` needs a ``pose`` (3,) attribute in the odometry frame (an
        :class:`~symloc.odometry.OdometryReading`); ``scan`` is whatever the tracker and the judge
        take (a :class:`~symloc.scan.LaserScan`).
        """
        odom_pose = np.asarray(odom.pose, dtype=np.float64)
        if isinstance(scan, LaserScan) and isinstance(odom, OdometryReading):
            # a spinning lidar's beams were taken along the last motion: undo it
            if self._last_odom is not None:
                v, w = twist_between(self._last_odom, odom)
                vx, vy, w = sensor_twist(v, w, self.laser_pose)
                scan = deskew(scan, vx, w, vy=vy)
            self._last_odom = odom
        result = self.tracker.update(odom, scan)
        if self._operator_pose is not None and self._operator_pose[2] is None:
            op, op_cov, _ = self._operator_pose
            self._operator_pose = (op, op_cov, odom_pose.copy())
        self._jumped = False
        if self.claim_gate is not None and result.updated:
            self._jumped = not self.claim_gate.anchor(result.estimate, result.covariance, odom_pose)
        verdict = self.judge(scan)
        self._last_result = result
        self._last_verdict = verdict
        self._odom_pose = odom_pose
        handler = {
            _Phase.LOST: self._on_lost,
            _Phase.TRACKING: self._on_tracking,
            _Phase.CENTERING: self._on_centering,
            _Phase.FACING: self._on_facing,
            _Phase.CAPTURE: self._on_capture,
            _Phase.ROTATING: self._on_rotating,
            _Phase.SETTLED: self._on_settled,
        }[self._phase]
        return handler(result, verdict, scan, image)

    # ------------------------------------------------------------------ internals

    def _reset_state(self) -> None:
        self._operator_pose = None
        self._suspended = False
        self._suspended_scans = 0
        self._resumed = 0
        self._unconverged = 0
        self._jumped = False
        self._converged_count = 0
        self._asym_count = 0
        self._centering_updates = 0
        self._order = 0
        self._centre_filter = CentreFilter(alpha=self.config.centre_smoothing)
        self._centre_map: FloatArray | None = None
        self._gv = float("nan")
        self._kind = ""
        self._attempt = 0
        self._m = 0
        self._rotate_start: float | None = None
        self._rotate_angle = 0.0
        self._outcomes: list[str] = []
        self._mapping_images: list[NDArray[np.uint8]] = []
        self._mapping_headings: list[float] = []
        self._mapping_heading0: float | None = None
        self._mapping = False
        self._settled_reason = ""
        self._candidate_place: Place | None = None
        self._last_result = None
        self._last_verdict = None
        self._odom_pose = np.zeros(3)

    def _note(self, text: str) -> None:
        self.log.append(text)

    def _converged(self, result: TrackerResult) -> bool:
        cfg = self.config
        if result.confident is not None:  # the tracker's verdict (symloc.mcl.confidence)
            return bool(result.confident)
        if not result.hypotheses:
            return False
        top = result.hypotheses[0]
        cov = np.asarray(result.covariance, dtype=np.float64)
        xy_std = math.sqrt(max(float(cov[0, 0]), float(cov[1, 1]), 0.0))
        th_std = math.sqrt(max(float(cov[2, 2]), 0.0))
        return (
            top.weight >= cfg.converged_weight
            and xy_std <= cfg.converged_xy_std
            and th_std <= cfg.converged_theta_std
        )

    def _centre_in_map(self, result: TrackerResult, verdict: SymmetryVerdict) -> FloatArray:
        assert verdict.center is not None
        c = compose(result.estimate, np.array([verdict.center[0], verdict.center[1], 0.0]))
        return np.asarray(c[:2], dtype=np.float64)

    def _known_place_at(self, pose: FloatArray) -> Place | None:
        best: Place | None = None
        best_d = math.inf
        for place in self.known_places:
            d = float(np.hypot(*(pose[:2] - place.center)))
            if d <= self.config.place_radius_factor * place.gv_distance and d < best_d:
                best, best_d = place, d
        return best

    def _copy_scores(self, copies: FloatArray, scan: object) -> FloatArray | None:
        """How well ``scan`` fits the map at each pose ``(k, 3)``: with a claim gate, each is
        first aligned to the map (a copy about an imprecise centre is a few centimetres off)
        and scored by the share of beams that fit; else the pose scorer's score; None without
        either."""
        if self.claim_gate is not None and isinstance(scan, LaserScan):
            return np.array([self.claim_gate.fit(c, scan)[1] for c in copies])
        if self.scorer is None:
            return None
        return np.asarray(self.scorer(copies, scan), dtype=np.float64)

    def _copies_verdict(
        self, pose: FloatArray, center: FloatArray, order: int, scan: object
    ) -> str | int:
        """``"unique"`` when every rotated copy of ``pose`` explains ``scan`` clearly worse,
        the index of a copy that explains it clearly better, else ``"ambiguous"``."""
        copies = rotated_copies(pose, center, order)
        scores = self._copy_scores(copies, scan)
        if scores is None:
            return "ambiguous"
        own = max(float(scores[0]), 1e-12)
        best = int(np.argmax(scores))
        if best != 0 and self.config.copy_score_ratio * float(scores[best]) >= own:
            return best
        if np.any(scores[1:] >= self.config.copy_score_ratio * own):
            return "ambiguous"
        return "unique"

    def _copies_fit(self, pose: FloatArray, center: FloatArray, order: int, scan: object) -> bool:
        """True when a rotated copy of ``pose`` explains ``scan`` about as well as ``pose``."""
        scores = self._copy_scores(rotated_copies(pose, center, order), scan)
        if scores is None:
            return True
        own = max(float(scores[0]), 1e-12)
        return bool(np.any(scores[1:] >= self.config.copy_score_ratio * own))

    def _copies_ambiguity(
        self, result: TrackerResult, pose: FloatArray, scan: object
    ) -> Estimate | None:
        """None when no rotated copy of ``pose`` (about a known symmetric place's centre or a
        near symmetry of the map) explains ``scan`` about as well; else the estimate that
        says so (going to the place's centre, or ambiguous among the map's copies, AMCL
        reseeded at a copy that fits clearly better). Every pose is checked so before it is
        first published: on convergence, and when a claim chain starts while tracking."""
        place = self._known_place_at(pose)
        if place is not None and self._copies_fit(pose, place.center, place.order, scan):
            self._converged_count = 0
            return self._start_ambiguity_at_place(result, place)
        for sym in self.map_symmetries:
            verdict = self._copies_verdict(pose, sym.centre, sym.order, scan)
            if verdict == "unique":
                continue
            self._converged_count = 0
            self._phase = _Phase.LOST
            copies = rotated_copies(pose, sym.centre, sym.order)
            if isinstance(verdict, int):
                # a rotated copy explains the scan clearly better: AMCL chose wrong
                self.tracker.initialize_pose(
                    copies[verdict],
                    _cov(self.config.reseed_xy_std, self.config.reseed_theta_std),
                )
                why = (
                    f"a rotated copy (order {sym.order}) of AMCL's pose explains the scan "
                    "clearly better: AMCL reseeded there, pose not earned yet"
                )
            else:
                why = (
                    f"the map itself is symmetric (order {sym.order}, overlap "
                    f"{100 * sym.overlap:.0f} %) and a rotated copy of AMCL's pose explains "
                    "the scan about as well: pose not earned"
                )
            if not self.log or self.log[-1] != why:
                self._note(why)
            return Estimate(
                status=Status.AMBIGUOUS,
                hypotheses=tuple(Hypothesis(pose=p, weight=1.0 / len(copies)) for p in copies),
                order=sym.order,
                reason=why,
            )
        return None

    def _candidates(self) -> tuple[Hypothesis, ...]:
        """The ``k`` candidate poses.

        From the scan and the place when a known place of this order and G-V distance has a
        regular-polygon verdict with an ``axis``: the robot sees the centre at ``c`` and a corner
        middle along ``axis`` (base frame); direction ``j`` of the place looks from the centre
        at a corner middle along ``heading0 - j 2 pi / M``, so ``theta_j = heading0 - j 2 pi / M
        - axis`` and ``p_j = centre_map - R(theta_j) c``. Otherwise: AMCL's estimate rotated about
        the centre.
        """
        v = self._last_verdict
        place = self._candidate_place
        if (
            place is not None
            and v is not None
            and v.symmetric
            and v.axis is not None
            and v.center is not None
            and place.m == self._order
        ):
            j = np.arange(place.m)
            theta = wrap_angle(place.heading0 - j * 2.0 * np.pi / place.m - v.axis)
            c, s = np.cos(theta), np.sin(theta)
            x = place.center[0] - (c * v.center[0] - s * v.center[1])
            y = place.center[1] - (s * v.center[0] + c * v.center[1])
            poses = np.column_stack([x, y, theta])
            return tuple(Hypothesis(pose=p, weight=1.0 / place.m) for p in poses)
        result = self._last_result
        if result is None or self._centre_map is None:
            return ()
        copies = rotated_copies(result.estimate, self._centre_map, self._order)
        w = 1.0 / len(copies)
        return tuple(Hypothesis(pose=p, weight=w) for p in copies)

    def _lost(self, reason: str, result: TrackerResult) -> Estimate:
        return Estimate(status=Status.LOST, hypotheses=result.hypotheses, reason=reason)

    def _claim(self, result: TrackerResult, scan: object, reason: str) -> Estimate:
        """Publish the tracker's estimate if the claim gate confirms it at this scan.

        A withdrawn claim or a jump of the filter suspends claims: they resume only when the
        last confirmed pose, carried by odometry, fits the scan again (a person walked past);
        after ``patience`` scans without that the pose is given up and AMCL relocalizes
        globally (the robot was carried away).
        """
        gate = self.claim_gate
        if gate is None:
            return self._tracking(result, reason)
        if not gate.anchored:
            gate.anchor(result.estimate, result.covariance, self._odom_pose)
        if self._jumped and not self._suspended and gate.has_chain:
            self._suspend("the filter's estimate jumped away from the tracked pose")
        if self._suspended:
            return self._while_suspended(result, scan, reason)
        if self._jumped:
            return self._unearned("the filter's estimate jumped", result)
        claim = gate.check(self._odom_pose, scan)  # type: ignore[arg-type]
        if claim.match is not None and claim.match.inlier_fraction < gate.config.min_claim_fit:
            # the scan stopped fitting where the operator put the robot (carried off?):
            # whatever the filter finds next is not the operator's choice among copies
            self._operator_pose = None
        if claim.ok:
            if not gate.has_chain and not self._at_operator_pose(claim.pose):
                assert claim.pose is not None
                copies = self._copies_ambiguity(result, claim.pose, scan)
                if copies is not None:
                    return copies
            return self._publish(claim, result, reason)
        if claim.verdict == "withdrawn" and not gate.has_chain:
            return self._unearned(claim.reason, result)
        if claim.verdict == "withdrawn" and gate.has_chain:
            self._suspend(claim.reason)
        return self._lost(claim.reason, result)

    def _at_operator_pose(self, pose: FloatArray | None) -> bool:
        """True when ``pose`` is the operator's initial pose carried by odometry (squared
        Mahalanobis distance within the gate's ``max_pull`` under the gate's odometry model):
        the operator chose among symmetric copies, so no copy check is needed. A pose the
        filter found elsewhere (the robot was carried off) is not the operator's choice."""
        gate = self.claim_gate
        if self._operator_pose is None or pose is None or gate is None:
            return False
        op, cov, odom0 = self._operator_pose
        if odom0 is None:
            return False
        carried, ccov = carry_by_odometry(op, cov, odom0, self._odom_pose, gate.alphas)
        e = np.asarray(pose, dtype=np.float64) - carried
        e[2] = float(wrap_angle(e[2]))
        if float(e @ np.linalg.solve(ccov, e)) <= gate.config.max_pull:
            return True
        self._operator_pose = None
        return False

    def _unearned(self, why: str, result: TrackerResult) -> Estimate:
        """Leave tracking when a pose that the laser never confirmed (an operator's initial
        pose, a reseed) is contradicted or abandoned by the filter: there is no confirmed pose
        to resume, and whatever the filter converges to next must be earned like any other
        (symmetric copies, known places), not published because the phase says tracking."""
        self._reset_state()
        self._phase = _Phase.LOST
        self._note(f"unconfirmed pose given up: {why}; the pose must be earned")
        return self._lost(f"unconfirmed pose given up: {why}", result)

    def _publish(self, claim: Claim, result: TrackerResult, reason: str) -> Estimate:
        assert self.claim_gate is not None
        assert claim.pose is not None
        assert claim.covariance is not None
        self.claim_gate.confirmed(claim, self._odom_pose)
        return Estimate(
            status=Status.TRACKING,
            pose=claim.pose,
            covariance=claim.covariance,
            hypotheses=result.hypotheses,
            reason=reason,
        )

    def _suspend(self, why: str) -> None:
        self._suspended = True
        self._suspended_scans = 0
        self._resumed = 0
        self._note(f"claims suspended: {why}")
        force = getattr(self.tracker, "force_update", None)
        if force is not None:
            force()

    def _while_suspended(self, result: TrackerResult, scan: object, reason: str) -> Estimate:
        gate = self.claim_gate
        assert gate is not None
        claim = gate.check(self._odom_pose, scan)  # type: ignore[arg-type]
        if claim.ok:
            self._resumed += 1
            if self._resumed >= gate.config.resume_after:
                self._suspended = False
                assert claim.pose is not None
                assert claim.covariance is not None
                if not gate.anchor(result.estimate, result.covariance, self._odom_pose) or (
                    self._jumped
                ):
                    # the filter went elsewhere while the pose continued: bring it back
                    self.tracker.initialize_pose(claim.pose, claim.covariance)
                gate.anchor(claim.pose, claim.covariance, self._odom_pose)
                self._note("claims resumed: the tracked pose fits the scan again")
                return self._publish(claim, result, reason)
            return self._lost("claims suspended: the tracked pose fits the scan again", result)
        self._resumed = 0
        self._suspended_scans += 1
        if self._suspended_scans >= gate.config.patience:
            self.tracker.initialize_global()
            gate.reset()
            self._reset_state()
            self._phase = _Phase.LOST
            why = (
                f"the tracked pose has not fitted the scan for {gate.config.patience} scans "
                "(kidnapped?): global relocalization, the pose must be earned again"
            )
            self._note(why)
            return self._lost(why, result)
        force = getattr(self.tracker, "force_update", None)
        if force is not None:
            force()
        return self._lost(f"claims suspended; {claim.reason}", result)

    def _tracking(self, result: TrackerResult, reason: str) -> Estimate:
        return Estimate(
            status=Status.TRACKING,
            pose=np.asarray(result.estimate, dtype=np.float64).copy(),
            covariance=np.asarray(result.covariance, dtype=np.float64).copy(),
            hypotheses=result.hypotheses,
            reason=reason,
        )

    def _ambiguous(self, status: Status, request: Request | None, reason: str) -> Estimate:
        return Estimate(
            status=status,
            hypotheses=self._candidates(),
            order=self._order,
            request=request,
            reason=reason,
        )

    # ---- LOST: nothing earned yet

    def _on_lost(self, result, verdict, scan, image) -> Estimate:  # type: ignore[no-untyped-def]
        if verdict.symmetric and verdict.center is not None:
            return self._start_ambiguity(result, verdict, scan, "scan symmetric, pose not earned")
        if self._converged(result):
            copies = self._copies_ambiguity(result, result.estimate, scan)
            if copies is not None:
                return copies
            self._converged_count += 1
            if self._converged_count >= self.config.converged_updates:
                self._phase = _Phase.TRACKING
                self._note("AMCL converged where the scan is not symmetric: pose earned")
                return self._claim(result, scan, "AMCL converged; scan not symmetric")
            return self._lost("AMCL converging", result)
        self._converged_count = 0
        if result.updated and self.claim_gate is not None:
            fits = self.claim_gate.check(self._odom_pose, scan).verdict != "withdrawn"
            self._unconverged = 0 if fits else self._unconverged + 1
        if self._unconverged >= self.config.relocalize_after:
            self.tracker.initialize_global()
            if self.claim_gate is not None:
                self.claim_gate.reset()
            self._unconverged = 0
            self._note(
                f"the scan contradicted AMCL's estimate for {self.config.relocalize_after} "
                "updates: global relocalization"
            )
            return self._lost("AMCL not converged; relocalizing globally", result)
        return self._lost("AMCL not converged", result)

    # ---- TRACKING: earned

    def _on_tracking(self, result, verdict, scan, image) -> Estimate:  # type: ignore[no-untyped-def]
        cfg = self.config
        if verdict.symmetric and verdict.center is not None:
            centre = self._centre_in_map(result, verdict)
            n = symmetry_consistent(
                result.hypotheses,
                centre,
                verdict.order,
                min_weight=cfg.min_cluster_weight,
                position_tol=cfg.symmetry_position_tol,
                angle_tol=cfg.symmetry_angle_tol,
            )
            if n >= 2:
                return self._start_ambiguity(
                    result, verdict, scan, f"AMCL split into {n} clusters related by the symmetry"
                )
        if not result.hypotheses or result.hypotheses[0].weight < cfg.min_cluster_weight:
            self._phase = _Phase.LOST
            self._note("AMCL lost its pose")
            return self._lost("AMCL has no well-weighted cluster", result)
        return self._claim(result, scan, "AMCL tracking")

    # ---- ambiguity: Algorithm 2

    def _start_ambiguity(self, result, verdict, scan, why: str) -> Estimate:  # type: ignore[no-untyped-def]
        self.particles_at_ambiguity = result.particles
        self._order = int(verdict.order)
        self._gv = float(verdict.gv_distance)
        self._kind = verdict.kind
        self._centre_map = self._centre_in_map(result, verdict)
        self._set_target(np.asarray(verdict.center, dtype=np.float64))
        found = [p for p in self.places.candidates(self._gv, self._order) if p.order == self._order]
        self._candidate_place = found[0] if len(found) == 1 else None
        self._phase = _Phase.CENTERING
        self._centering_updates = 0
        self._asym_count = 0
        self._outcomes = []
        self._note(f"ambiguous (order {_order_people(self._order)}): {why}; going to the centre")
        return self._ambiguous(
            Status.AMBIGUOUS,
            Request(RequestKind.GO_TO_CENTRE, target=np.asarray(verdict.center, dtype=float)),
            f"{why}; order {_order_people(self._order)}",
        )

    def _start_ambiguity_at_place(self, result: TrackerResult, place: Place) -> Estimate:
        self.particles_at_ambiguity = result.particles
        self._order = place.order
        self._gv = place.gv_distance
        self._kind = place.kind
        self._centre_map = np.asarray(place.center, dtype=np.float64)
        self._candidate_place = place
        # every rotated copy of the estimate sees the place's centre at the same base-frame point
        centre_base = compose(inverse(result.estimate), np.array([*place.center, 0.0]))[:2]
        self._set_target(centre_base)
        self._phase = _Phase.CENTERING
        self._centering_updates = 0
        self._asym_count = 0
        self._outcomes = []
        why = f"inside known symmetric place {place.place_id}: rotated copies fit the map"
        self._note(f"ambiguous (order {_order_people(self._order)}): {why}")
        return self._ambiguous(
            Status.AMBIGUOUS, Request(RequestKind.GO_TO_CENTRE, target=centre_base), why
        )

    def _set_target(self, centre_base: FloatArray) -> None:
        self._centre_filter.update(self._odom_pose, centre_base[:2])

    def _target_base(self) -> FloatArray:
        target = self._centre_filter.update(self._odom_pose, None)
        assert target is not None
        return target

    def _track_verdict(self, verdict: SymmetryVerdict) -> bool:
        """Update the target from a symmetric verdict; False when the verdict flipped for good."""
        if verdict.symmetric and verdict.center is not None:
            self._asym_count = 0
            self._set_target(np.asarray(verdict.center, dtype=np.float64))
            self._gv = float(verdict.gv_distance)
            return True
        self._asym_count += 1
        return self._asym_count < self.config.flip_patience

    def _abandon(self, result: TrackerResult, why: str) -> Estimate:
        self._note(f"gave up the trip to the centre: {why}")
        self._reset_state()
        self._last_result = result
        self._phase = _Phase.LOST
        return self._lost(why, result)

    def _on_centering(self, result, verdict, scan, image) -> Estimate:  # type: ignore[no-untyped-def]
        self._centering_updates += 1
        if not self._track_verdict(verdict):
            return self._abandon(result, "the scan is no longer judged symmetric")
        if self._centering_updates > self.config.max_centering_updates:
            return self._abandon(result, "did not reach the centre in time")
        target = self._target_base()
        if float(np.hypot(*target)) <= self.config.centre_tolerance and verdict.symmetric:
            self._phase = _Phase.FACING
            self._note("reached the centre")
            return self._on_facing(result, verdict, scan, image)
        return self._ambiguous(
            Status.GOING_TO_CENTRE,
            Request(RequestKind.GO_TO_CENTRE, target=target),
            f"going to the centre ({1000 * float(np.hypot(*target)):.0f} mm away)",
        )

    def _on_facing(self, result, verdict, scan, image) -> Estimate:  # type: ignore[no-untyped-def]
        self._centering_updates += 1
        if not self._track_verdict(verdict):
            return self._abandon(result, "the scan is no longer judged symmetric")
        if self._centering_updates > self.config.max_centering_updates:
            return self._abandon(result, "could not face the corner middle in time")
        facing = verdict.facing if verdict.symmetric else None
        if facing is None or abs(facing) <= self.config.facing_tolerance:
            return self._begin_capture()
        return self._ambiguous(
            Status.GOING_TO_CENTRE,
            Request(RequestKind.FACE_DIRECTION, angle=float(facing)),
            "at the centre; facing the middle between two adjacent corners",
        )

    # ---- DECIDING: Algorithm 3 and the G-V lookup

    def _m_for(self, candidates: Sequence[Place]) -> int:
        if candidates:
            return max(p.m for p in candidates)
        return directions_for(self._kind, self._order)

    def _begin_capture(self) -> Estimate:
        self._phase = _Phase.CAPTURE
        if self._m == 0:
            self._m = self._m_for(self.places.candidates(self._gv, self._order))
        return self._ambiguous(
            Status.DECIDING,
            Request(RequestKind.CAPTURE_IMAGE),
            f"at the centre; image {self._attempt + 1} of {self._m} requested",
        )

    def _on_capture(self, result, verdict, scan, image) -> Estimate:  # type: ignore[no-untyped-def]
        if image is None:
            return self._ambiguous(
                Status.DECIDING, Request(RequestKind.CAPTURE_IMAGE), "waiting for the image"
            )
        if self._mapping:
            return self._collect_mapping_image(result, image)
        candidates = list(self.places.candidates(self._gv, self._order))
        if self._centre_map is not None and len(candidates) > 1:
            centre = self._centre_map
            candidates.sort(key=lambda p: float(np.hypot(*(p.center - centre))))
        decisions: list[tuple[Place, Decision]] = [
            (p, self.places.decide(p, image)) for p in candidates
        ]
        decided = [(p, d) for p, d in decisions if d.status == "decided"]
        if decided:
            if len(decided) > 1:
                decided.sort(key=lambda pd: -pd[1].score)
                if decided[1][1].score >= 0.8 * decided[0][1].score:
                    self._outcomes.append("undetermined")
                    return self._next_attempt("two places decided alike")
            place, dec = decided[0]
            if not place.heading_reliable:
                return self._unanchored(place, dec)
            return self._reseed(result, place, dec, scan)
        if not candidates:
            self._outcomes.append("no_place")
        elif all(d.status == "refused" for _, d in decisions):
            self._outcomes.append("refused")
        elif all(d.status == "no_match" for _, d in decisions):
            self._outcomes.append("no_match")
        else:
            self._outcomes.append("undetermined")
        last = decisions[0][1].reason if decisions else "no place with this G-V distance"
        self._note(f"image {self._attempt + 1}: {self._outcomes[-1]} ({last})")
        return self._next_attempt(last)

    def _reseed(self, result: TrackerResult, place: Place, dec: Decision, scan: object) -> Estimate:
        """The decision picked the copy; the laser sets the pose from it, then AMCL reseeds."""
        assert dec.direction is not None
        if dec.heading is not None:
            heading = float(wrap_angle(dec.heading))
        else:
            heading = wrap_angle(
                place.heading0 - dec.direction * 2.0 * np.pi / place.m + dec.offset
            )
        self.last_decision = (place, dec)
        pose = np.array([place.center[0], place.center[1], heading])
        cov = _cov(self.config.decision_xy_std, self.config.decision_theta_std)
        reason = (
            f"visual decision: place {place.place_id},"
            f" direction {_people(dec.direction)} of {place.m}"
        )
        gate = self.claim_gate
        claim = None
        if gate is not None:
            claim = gate.confirm(pose, cov, scan)  # type: ignore[arg-type]
            if claim.verdict == "withdrawn":
                self._outcomes.append("undetermined")
                self._note(
                    f"image {self._attempt + 1}: direction {_people(dec.direction)} of place "
                    f"{place.place_id} rejected by the laser ({claim.reason})"
                )
                return self._next_attempt("the laser rejected the decided pose")
            assert claim.pose is not None
            assert claim.covariance is not None
            pose, cov = claim.pose, claim.covariance
            reason += "; pose set by the laser"
        if self._last_result is not None:
            self.particles_before_decision = self._last_result.particles
        reseed_cov = np.maximum(cov, _cov(self.config.reseed_xy_std, self.config.reseed_theta_std))
        self.tracker.initialize_pose(pose, reseed_cov)
        self._note(
            f"decided direction {_people(dec.direction)} of {place.m} at place {place.place_id}"
            f" (offset {math.degrees(dec.offset):+.1f} deg); AMCL reseeded"
        )
        if claim is not None and gate is not None:
            if claim.verdict == "withheld":
                return self._settle(
                    "undetermined: the decided pose is not certain enough for the tolerance "
                    f"({claim.reason.removeprefix('claim withheld: ')}); pose not claimed"
                )
            gate.anchor(pose, cov, self._odom_pose)
            gate.confirmed(claim, self._odom_pose)
        self._reset_state()
        self._phase = _Phase.TRACKING
        return Estimate(
            status=Status.TRACKING,
            pose=pose,
            covariance=cov,
            hypotheses=(Hypothesis(pose=pose, weight=1.0),),
            reason=reason,
        )

    def _unanchored(self, place: Place, dec: Decision) -> Estimate:
        """A direction was decided, but the place's heading reference is odometry's: no claim."""
        self.last_decision = (place, dec)
        self._note(
            f"decided direction {_people(dec.direction)} of {place.m} at place"
            f" {place.place_id}, but its stored "
            "headings came from odometry (not observable by the laser when it was mapped)"
        )
        return self._settle(
            "undetermined: the visual map of this place has no reliable heading reference "
            "(mapped where laser SLAM cannot observe heading); pose not claimed"
        )

    def _next_attempt(self, why: str) -> Estimate:
        self._attempt += 1
        if self._attempt >= self._m:
            return self._conclude()
        self._phase = _Phase.ROTATING
        self._rotate_start = float(self._odom_pose[2])
        # a polygon squares up on the next corner middle after the turn; a circle has none, and
        # a query half-way between two stored views scores both alike, so it turns half a step
        step = 2.0 * np.pi / self._m if self._order != 0 else np.pi / self._m
        self._rotate_angle = -step
        return self._ambiguous(
            Status.DECIDING,
            Request(RequestKind.ROTATE, angle=self._rotate_angle),
            f"attempt {self._attempt}: {why}; turning clockwise by {np.degrees(step):.0f} deg",
        )

    def _on_rotating(self, result, verdict, scan, image) -> Estimate:  # type: ignore[no-untyped-def]
        assert self._rotate_start is not None
        turned = float(angle_diff(self._odom_pose[2], self._rotate_start))
        remaining = float(angle_diff(self._rotate_angle, turned))
        if abs(remaining) <= self.config.rotate_tolerance:
            self._rotate_start = None
            self._phase = _Phase.FACING
            self._centering_updates = 0
            return self._on_facing(result, verdict, scan, image)
        return self._ambiguous(
            Status.DECIDING,
            Request(RequestKind.ROTATE, angle=remaining),
            f"turning to direction {self._attempt + 1} of {self._m}",
        )

    def _conclude(self) -> Estimate:
        outcomes = set(self._outcomes)
        nothing_matched = outcomes <= {"no_place", "no_match"}
        if nothing_matched and self.config.allow_mapping and self._order >= 2:
            self._mapping = True
            self._attempt = 0
            self._mapping_images = []
            self._mapping_headings = []
            self._mapping_heading0 = None
            self._phase = _Phase.CAPTURE
            self._note("no visual map matches this place: building one (Algorithm 5 step 11)")
            return self._ambiguous(
                Status.DECIDING,
                Request(RequestKind.CAPTURE_IMAGE),
                f"no visual map matches: mapping this place, image 1 of {self._m}",
            )
        if "refused" in outcomes and len(outcomes) == 1:
            why = "undetermined: the images have too few features to decide"
        elif nothing_matched:
            why = "undetermined: no visual map matches this place (mapping not allowed)"
        else:
            why = f"undetermined: no clear visual decision in {self._m} directions"
        return self._settle(why)

    def _settle(self, why: str) -> Estimate:
        self._phase = _Phase.SETTLED
        self._settled_reason = why
        self._asym_count = 0
        self._note(why)
        return self._ambiguous(Status.AMBIGUOUS, None, why)

    def _collect_mapping_image(self, result: TrackerResult, image: NDArray[np.uint8]) -> Estimate:
        if self._mapping_heading0 is None:
            self._mapping_heading0 = float(result.estimate[2])
        self._mapping_images.append(image)
        self._mapping_headings.append(float(result.estimate[2]))
        if len(self._mapping_images) < self._m:
            self._attempt = len(self._mapping_images)
            self._phase = _Phase.ROTATING
            self._rotate_start = float(self._odom_pose[2])
            self._rotate_angle = -2.0 * np.pi / self._m
            return self._ambiguous(
                Status.DECIDING,
                Request(RequestKind.ROTATE, angle=self._rotate_angle),
                f"mapping this place: turning clockwise for image {self._attempt + 1}",
            )
        assert self._centre_map is not None
        args = (
            self._centre_map,
            self._mapping_heading0,
            self._order,
            self._gv,
            self._kind,
            list(self._mapping_images),
        )
        # measured headings when the store takes them (stores written before that keyword exist)
        if "headings" in inspect.signature(self.places.add_place).parameters:
            place = self.places.add_place(*args, headings=list(self._mapping_headings))
        else:
            place = self.places.add_place(*args)
        self.known_places.append(place)
        self._mapping = False
        return self._settle(
            f"new visual map built for place {place.place_id}; its heading reference is "
            f"AMCL's choice among {self._order} symmetric copies, so the pose stays ambiguous"
        )

    # ---- SETTLED: ambiguous, nothing more to try until the scan changes

    def _on_settled(self, result, verdict, scan, image) -> Estimate:  # type: ignore[no-untyped-def]
        if verdict.symmetric:
            self._asym_count = 0
            return self._ambiguous(Status.AMBIGUOUS, None, self._settled_reason)
        self._asym_count += 1
        if self._asym_count >= self.config.flip_patience:
            self.tracker.initialize_global()
            self._reset_state()
            self._phase = _Phase.LOST
            self._note("left the symmetric place: global AMCL, pose must be earned again")
            return self._lost("left the symmetric place; relocalizing", result)
        return self._ambiguous(Status.AMBIGUOUS, None, self._settled_reason)
