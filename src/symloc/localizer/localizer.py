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

Each scan goes update -> deskew -> tracker -> claim gate's anchor -> judge -> the phase's step
(:mod:`symloc.localizer.phases`); the phases share the collaborators through one
:class:`~symloc.localizer.context.Context`. With ``LocalizerConfig.decide_here`` set, a scan
that would go to :class:`~symloc.localizer.phases.Lost` goes first to
:class:`~symloc.localizer.decide_here.DecideHere` (the laser proposes, the camera decides where
the robot stands; :class:`~symloc.localizer.decide_here.DecideRouter`).
"""

from __future__ import annotations

import logging
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from symloc.errors import ConfigurationError
from symloc.grid import OccupancyGrid
from symloc.odometry import OdometryReading, twist_between
from symloc.scan import LaserScan, deskew, sensor_twist

from .claim import ClaimGate
from .config import LocalizerConfig
from .context import Context, DecideCounts, Inputs, Record
from .copies import PoseScorer, rotated_copies, symmetry_consistent
from .decide_here import DecideRouter
from .map_symmetry import MapSymmetry
from .notes import NOTE_HISTORY, Notes
from .phases import Lost, Phase, Tracking, restart
from .types import (
    Decision,
    Estimate,
    KeyframeStore,
    Place,
    PlaceStore,
    PoseProposer,
    SymmetryJudge,
    Tracker,
    TrackerResult,
    Verification,
)

__all__ = ["Localizer", "LocalizerConfig", "rotated_copies", "symmetry_consistent"]

FloatArray = NDArray[np.float64]

logger = logging.getLogger(__name__)


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
    note_history : int, optional
        How many notes :attr:`log` keeps (they also go to this module's logger).
    proposer : PoseProposer, optional
        The laser's proposals from one scan (the global scan-to-map search); used when
        ``config.decide_here`` is set (:mod:`symloc.localizer.decide_here`).
    keyframes : KeyframeStore, optional
        The visual map's keyframes, against which the camera verifies hypotheses where the
        robot stands (``config.decide_here``).
    grid : OccupancyGrid, optional
        The map, for where a corridor's axis runs on into space the map does not cover
        (:mod:`symloc.localizer.axis_phase`; None: the axis ends where the scan stops fitting).
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
        map_symmetries: Sequence[MapSymmetry] = (),
        claim_gate: ClaimGate | None = None,
        laser_pose: FloatArray | Sequence[float] = (0.0, 0.0, 0.0),
        note_history: int = NOTE_HISTORY,
        proposer: PoseProposer | None = None,
        keyframes: KeyframeStore | None = None,
        grid: OccupancyGrid | None = None,
    ) -> None:
        lp = np.asarray(laser_pose, dtype=np.float64).reshape(-1)
        if lp.shape != (3,) or not np.all(np.isfinite(lp)):
            raise ConfigurationError(
                f"Localizer.laser_pose: expected finite (x, y, yaw), got {lp.tolist()}"
            )
        #: the laser in the robot frame (``base_from_laser``), see the class docstring
        self.laser_pose = lp
        self.judge = judge
        #: what the localizer did, in words: the last ``note_history`` notes
        self.log = Notes(logger, note_history)
        self._ctx = Context(
            tracker=tracker,
            places=places,
            config=config if config is not None else LocalizerConfig(),
            gate=claim_gate,
            scorer=scorer,
            known_places=list(known_places),
            map_symmetries=list(map_symmetries),
            notes=self.log,
            record=Record(),
            proposer=proposer,
            keyframes=keyframes,
            grid=grid,
        )
        #: sends the localizer to decide where it stands (``config.decide_here``), else None
        self._router = DecideRouter() if self._ctx.config.decide_here else None
        self._last_odom: OdometryReading | None = None
        self._last_result: TrackerResult | None = None
        self._phase: Phase = Lost.fresh(self.config)

    # ------------------------------------------------------------------ collaborators

    @property
    def tracker(self) -> Tracker:
        """The laser tracker (AMCL)."""
        return self._ctx.tracker

    @property
    def places(self) -> PlaceStore:
        """The visual map with its G-V index."""
        return self._ctx.places

    @property
    def config(self) -> LocalizerConfig:
        """The localizer's settings."""
        return self._ctx.config

    @property
    def scorer(self) -> PoseScorer | None:
        """The pose scorer used for the copy checks without a claim gate."""
        return self._ctx.scorer

    @property
    def claim_gate(self) -> ClaimGate | None:
        """Every pose published as tracking passes this gate (:mod:`symloc.localizer.claim`);
        None publishes the tracker's estimate unchecked (scripted tests only)."""
        return self._ctx.gate

    @property
    def known_places(self) -> list[Place]:
        """Symmetric places of the map; a place mapped by the localizer is appended."""
        return self._ctx.known_places

    @property
    def map_symmetries(self) -> Sequence[MapSymmetry]:
        """Rotational symmetries of the map itself: a converged pose whose rotated copy fits
        the scan as well is not earned."""
        return self._ctx.map_symmetries

    # ------------------------------------------------------------------ what callers read

    @property
    def phase(self) -> str:
        """The internal phase name (finer than the status; for logs and tests)."""
        return self._phase.name

    @property
    def last_decision(self) -> tuple[Place, Decision] | None:
        """(place, decision) of the last visual decision that reseeded AMCL."""
        return self._ctx.record.last_decision

    @property
    def holds_pose(self) -> bool:
        """True while the localizer still vouches for its last confirmed pose: it is tracking
        and its claims are not suspended (a scan whose claim was only withheld keeps the pose;
        a withdrawn claim, a jump of the filter, ambiguity or a lost pose do not). Read only:
        the ROS node keeps ``map -> odom`` on the last confirmed pose while this holds."""
        if not isinstance(self._phase, Tracking):
            return False
        gate = self.claim_gate
        return gate is None or not gate.suspended

    @property
    def last_result(self) -> TrackerResult | None:
        """The tracker's result at the last scan (its estimate, clusters, particles (N, 3) and
        weights (N,), for display: a pose there is not earned); None before the first scan."""
        return self._last_result

    @property
    def particles_at_ambiguity(self) -> FloatArray | None:
        """AMCL's particles (N, 3) when the ambiguity was declared (for figures)."""
        return self._ctx.record.particles_at_ambiguity

    @property
    def particles_before_decision(self) -> FloatArray | None:
        """AMCL's particles (N, 3) just before the visual decision reseeded it (for figures)."""
        return self._ctx.record.particles_before_decision

    @property
    def last_camera_check(self) -> tuple[FloatArray, Verification] | None:
        """The camera's last check of the hypotheses while deciding here: their map poses
        (K, 3) when the image was taken and the :class:`Verification` (one verdict with its
        inliers per hypothesis, the one chosen if any); None before any (for figures)."""
        return self._ctx.record.last_camera_check

    @property
    def decide_counts(self) -> DecideCounts:
        """What deciding from where the robot stands did so far (``config.decide_here``)."""
        return self._ctx.record.decide

    # ------------------------------------------------------------------ commands

    def reset_global(self) -> None:
        """Forget the pose (start-up or kidnapping): global AMCL, nothing earned."""
        self.tracker.initialize_global()
        if self._router is not None:
            self._router.reset()
        self._enter(restart(self._ctx))
        self.log("reset: global initialisation, pose not earned")

    def set_pose(self, pose: FloatArray, covariance: FloatArray) -> None:
        """A pose given by the operator (like RViz's 2D Pose Estimate): reseed and earn it."""
        self.tracker.initialize_pose(np.asarray(pose, float), np.asarray(covariance, float))
        if self._router is not None:
            self._router.reset()
        fresh = restart(self._ctx)
        if self.claim_gate is not None:
            # the operator chose among any symmetric copies (the laser still confirms the pose)
            self.claim_gate.start_at_operator_pose(pose, covariance)
        self._enter(Tracking(fresh, from_operator=True))
        self.log("pose set by the operator")

    def force_update(self) -> None:
        """Integrate the next scan even if the robot has not moved (nav2's
        ``request_nomotion_update``)."""
        self.tracker.force_update()

    def update(
        self, odom: OdometryReading, scan: object, image: NDArray[np.uint8] | None = None
    ) -> Estimate:
        """One step: odometry reading, laser scan and, if one was requested, an image.

        ``odom`` needs a ``pose`` (3,) attribute in the odometry frame (an
        :class:`~symloc.odometry.OdometryReading`); ``scan`` is whatever the tracker and the judge
        take (a :class:`~symloc.scan.LaserScan`).
        """
        odom_pose = np.asarray(odom.pose, dtype=np.float64)
        turn_rate = 0.0
        if isinstance(scan, LaserScan) and isinstance(odom, OdometryReading):
            # a spinning lidar's beams were taken along the last motion: undo it
            if self._last_odom is not None:
                v, w = twist_between(self._last_odom, odom)
                turn_rate = abs(w)
                vx, vy, w = sensor_twist(v, w, self.laser_pose)
                scan = deskew(scan, vx, w, vy=vy)
            self._last_odom = odom
        result = self.tracker.update(odom, scan)
        self._last_result = result
        if self.claim_gate is not None:
            self.claim_gate.observe(result, odom_pose)
        verdict = self.judge(scan)
        inputs = Inputs(result, verdict, scan, image, odom_pose, turn_rate)
        phase = self._phase
        if self._router is not None:
            phase = self._router.route(self._ctx, inputs, phase)
        estimate, after = phase.step(self._ctx, inputs)
        if self._router is not None:
            self._router.after(phase, after)
        self._enter(after)
        return estimate

    def _enter(self, phase: Phase) -> None:
        """The one transition: a confirmed pose vouches for the next one only while tracking
        lasts, so any other phase forgets the claim chain."""
        if not isinstance(phase, Tracking) and self.claim_gate is not None:
            self.claim_gate.forget_chain()
        self._phase = phase
