"""The laser SLAM pipeline: local scan-to-submap matching, loop closures, GTSAM back end.

For every scan (Hess et al. 2016 structure, with Olson's correlative matcher):

1. **Predict** its local pose from the previous one and the odometry increment, corrected by
   the odometry's learnt calibration, with a covariance from its learnt noise
   (:class:`~symloc.slam.odometry_model.OdometryModel`).
2. **Match** it against the oldest active submap in a window of about three predicted
   standard deviations (:func:`match_scan`; a wider retry when it scores poorly), and find
   which directions the match constrains (:func:`~symloc.slam.degeneracy.analyse_match`).
   **Fuse** match and prediction by their covariances: along a direction the scan does not
   constrain (a corridor's axis, an open hall), the pose follows the odometry instead of
   sliding. Insert the scan into the active submaps (:class:`ActiveSubmaps`).
3. **Graph**: add the node, its intra-submap constraints (the match covariance: loose along
   unconstrained directions) and the odometry constraint (the learnt noise).
4. **Loop closure** (every ``loop_every`` nodes): match the scan against the
   ``loop_max_candidates`` nearest finished older submaps whose predicted distance is below
   ``loop_search_distance``, in a window that grows with the drift since the last accepted
   closure; each candidate is verified (:class:`~symloc.slam.loop_closure.LoopVerifier`:
   score, ambiguity against the runner-up, degeneracy, consistency with the current estimate
   and with other closures) before it enters the graph with a robust loss. Loop searches are
   sampled along the trajectory, as Cartographer samples them (its ``sampling_ratio``) but by
   distance: a submap is searched again only after the robot travelled
   ``loop_resample_distance`` since its last search, and ``loop_constrained_distance`` after
   a search that found a loop.
5. **Optimise** with Levenberg-Marquardt every ``optimize_every`` nodes when new loop
   constraints arrived, and once at the end; loops the optimised graph still disagrees with
   are removed (:meth:`PoseGraph.check_loops`).

Finally all scans are integrated at their optimised poses into one log-odds grid, returned
as an :class:`~symloc.grid.OccupancyGrid`, with the warnings that make a result doubtful
(:attr:`SlamResult.warnings`).

Memory grows with the mapped area: finished submaps keep only their occupied cells, and
likelihood tables are cached within ``table_cache_mb``.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time
from collections import OrderedDict, deque
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray
from tqdm import tqdm

from symloc._checks import check_array, check_positive
from symloc.errors import ConfigurationError
from symloc.geometry import compose, inverse, relative, wrap_angle
from symloc.grid.log_odds import InverseSensorModel, LogOddsGrid
from symloc.grid.occupancy_grid import OccupancyGrid
from symloc.scan import LaserScan
from symloc.slam.correlative_scan_matching import CsmParams, match_scan, refine_pose
from symloc.slam.degeneracy import (
    UNCONSTRAINED_SIGMA,
    MatchConstraint,
    analyse_match,
    fuse,
    scan_information,
)
from symloc.slam.loop_closure import LoopCandidate, LoopVerifier, LoopVerifierParams
from symloc.slam.map_refinement import density_table, nodes_in_map
from symloc.slam.odometry_model import OdometryModel, OdometryModelParams
from symloc.slam.pose_graph import PoseGraph, PoseGraphParams
from symloc.slam.pose_marginals import map_error_field
from symloc.slam.submaps import ActiveSubmaps, Submap, SubmapParams

if TYPE_CHECKING:  # imported where used: it brings the localizer's compiled kernels
    from symloc.grid.map_error_field import MapErrorField
    from symloc.slam.map_error import MapError

__all__ = [
    "ODOMETRY_HEADING_STEP",
    "SlamParams",
    "SlamResult",
    "run_slam",
    "scan_points",
    "slam_input",
]

FloatArray = NDArray[np.float64]

_LOG = logging.getLogger(__name__)


@dataclass(frozen=True, slots=True)
class SlamParams:
    """Settings of the whole pipeline: one configuration for every log and odometry.

    Parameters
    ----------
    submap : SubmapParams
    local_csm : CsmParams
        Real-time matching settings; its windows are replaced per scan by ``window_sigmas``
        predicted standard deviations, clamped to ``[min_window, local_csm.*_window]``.
    window_sigmas : float
        Real-time search half-width in predicted standard deviations.
    min_submap_scans : int
        Scans a submap needs before scans are matched against it (the first scans of a run
        follow the odometry: one scan's far walls are dotted, which a match reads as
        features).
    min_linear_window, min_angular_window : float
        Smallest real-time search half-widths [m], [rad].
    retry_csm : CsmParams
        Wider window tried when the real-time match scores below ``retry_below``: its
        windows, or twice the real-time ones up to ``max_retry_window`` ([m], [rad]); the
        better of the two matches is kept.
    max_retry_window : tuple of 2 floats
    retry_below : float
        Score (0..1) under which the wider search runs, or ``retry_relative`` times the
        median score of the last 50 matches if that is lower (scans of another scanner, or
        logged a metre apart, match less well everywhere: a low score is relative).
    retry_relative : float
        See ``retry_below``.
    unusable_relative : float
        A match scoring below this times the run's median score (and below
        ``retry_below * unusable_relative / retry_relative``) is not used: the scan follows
        the odometry.
    loop_score_relative, loop_score_floor : float
        A loop closure needs ``loop.min_score``, or ``loop_score_relative`` times the run's
        median real-time score if that is lower, but at least ``loop_score_floor``.
    retry_margin : float
        The wide match replaces the real-time one only if it scores this much higher (a
        corridor gives many similar scores far from the odometry; a real odometry error gives
        a clearly better one) and is not poor itself. A match that stays poor is not used:
        the scan follows the odometry.
    fuse_odometry : bool
        Fuse each match with the odometry prediction by their covariances (False: the match
        decides every direction it constrains, the prediction only the others).
    match_gate_chi2 : float
        The odometry gate: a match that scores below the run's median score and whose
        difference from the prediction exceeds this squared Mahalanobis distance (prediction
        and match covariances; default the 99.9 % quantile of chi-square with 3 degrees of
        freedom) is not used, and the scan follows the odometry...
    gate_recovery : int
        ... unless the ``gate_recovery`` matches before it were refused too: matches that keep
        disagreeing mean the odometry was wrong (a wheel slipped), and the match is taken.
    loop_csm : CsmParams
        Loop-closure matching settings; its windows are the smallest ones, grown by the
        drift since the last accepted closure up to ``max_loop_window``.
    max_loop_window : tuple of 2 floats
        Largest loop search half-widths ([m], [rad]).
    odometry : OdometryModelParams
        The learnt calibration and noise of the odometry.
    degeneracy_threshold : float
        Relative eigenvalue of a scan's point-to-line information below which its direction
        counts as unconstrained (:func:`~symloc.slam.degeneracy.analyse_match`).
    min_surface_fraction : float
        A scan whose strongest direction is faced by fewer than this fraction of its points
        constrains nothing (few returns).
    min_match_sigma, min_match_rot : float
        Smallest standard deviations [m], [rad] given to a scan match.
    loop : LoopVerifierParams
    loop_ambiguity_radius : tuple of 2 floats
        ``(m, rad)``: the neighbourhood of the best loop match outside which the runner-up is
        searched.
    graph : PoseGraphParams
    max_range : float
        Points farther than this [m] are not used for matching.
    voxel : float
        Points are thinned to one per ``voxel`` x ``voxel`` square [m] for matching (0: off).
    motion_filter_distance, motion_filter_angle : float
        A scan becomes a graph node (inserted into the submaps, searched for loop closures)
        only if the robot moved at least this far [m] or turned this much [rad] since the last
        node (Cartographer's motion filter); the final pose of another scan follows its last
        node. 0 and 0 make every scan a node.
    match_filtered_scans : bool
        Also scan-match the scans the motion filter drops.
    loop_every : int
        Search loop closures for every ``loop_every``-th node.
    loop_search_distance : float
        Largest distance [m] between a node's predicted position and the centre of a submap's
        nodes for a loop search.
    loop_skip_submaps : int
        The newest finished submaps skipped by the loop search (they are local matches).
    loop_max_candidates : int
        At most this many submaps (the nearest) are matched per searched node.
    loop_resample_distance : float
        Trajectory length [m] the robot must travel after a loop search of a submap before
        that submap is searched again (0: search it at every searched node).
    loop_constrained_distance : float
        Same after a search of the submap that found a loop closure (0: no extra wait).
    optimize_every : int
        Nodes between optimisations when new loop closures arrived.
    map_resolution : float
        Cell edge of the final map [m].
    refine_rounds : int
        Rounds of the final scan-to-map refinement (:mod:`symloc.slam.map_refinement`): each
        node's scan aligned with the point density of all node scans, added to the graph as
        a prior with the match's covariance, and the graph optimised again (0: off).
    refine_resolution, refine_sigma : float
        Cell edge [m] and Gaussian blur [m] of that density.
    refine_max_cells : int
        Largest density grid (cells); a larger map is not refined (a warning says so).
    refine_degeneracy_threshold : float
        Relative eigenvalue below which a direction of a refined node counts as
        unconstrained (see ``degeneracy_threshold``; far lower, as many nodes share it).
    refine_max_correction : tuple of 2 floats
        ``(m, rad)``: a node whose scan-to-map match moves it farther is left out of that
        round (a look-alike wall, a scan of people).
    map_clamp : bool
        Clamp the final map's log-odds after every scan as the submaps do (False, the
        default: the final map sums all the evidence, so a wall's cells are judged by all the
        beams that reached them, not by the last few; see
        :class:`~symloc.grid.log_odds.LogOddsGrid`).
    map_error : bool
        Estimate the final map's own error from its node scans aligned again to it
        (:mod:`symloc.slam.map_error`; :attr:`SlamResult.map_error`, written beside a saved
        map) and move the map by the shift those alignments share, so that a scan aligned to
        the map lands where SLAM put it: the surface a localizer aligns to lies on a wall
        band's centre line, up to half a cell from the hits that drew it (2-3 cm at 5 cm
        cells). Skipped on maps above ``refine_max_cells`` cells. Also the map's error place
        by place from the pose graph's marginals (:mod:`symloc.slam.pose_marginals`,
        :attr:`SlamResult.map_error_field`), on any map.
    table_cache_mb : float
        Memory budget [MiB] of the cached submap likelihood tables (least recently matched
        dropped first; a dropped table is rebuilt from the submap's occupied cells).
    """

    submap: SubmapParams = field(default_factory=SubmapParams)
    local_csm: CsmParams = field(
        default_factory=lambda: CsmParams(
            linear_window=2.0,
            angular_window=math.radians(45),
            coarse_factor=6,
            translation_weight=1.0,
            rotation_weight=1.0,
        )
    )
    window_sigmas: float = 3.0
    min_submap_scans: int = 1
    min_linear_window: float = 0.15
    min_angular_window: float = math.radians(4.0)
    retry_csm: CsmParams = field(
        default_factory=lambda: CsmParams(
            linear_window=1.5,
            angular_window=math.radians(40),
            coarse_factor=8,
            translation_weight=0.3,
            rotation_weight=0.3,
        )
    )
    max_retry_window: tuple[float, float] = (4.0, math.radians(60.0))
    retry_below: float = 0.6
    retry_relative: float = 0.85
    unusable_relative: float = 0.3
    loop_score_relative: float = 1.0
    loop_score_floor: float = 0.35
    retry_margin: float = 0.1
    fuse_odometry: bool = False
    match_gate_chi2: float = 16.27
    gate_recovery: int = 2
    loop_csm: CsmParams = field(
        default_factory=lambda: CsmParams(
            linear_window=1.0, angular_window=math.radians(8), coarse_factor=8
        )
    )
    max_loop_window: tuple[float, float] = (3.0, math.radians(30.0))
    odometry: OdometryModelParams = field(default_factory=OdometryModelParams)
    degeneracy_threshold: float = 0.05
    min_surface_fraction: float = 0.05
    min_match_sigma: float = 0.01
    min_match_rot: float = math.radians(0.25)
    loop: LoopVerifierParams = field(default_factory=LoopVerifierParams)
    loop_ambiguity_radius: tuple[float, float] = (0.3, math.radians(3.0))
    graph: PoseGraphParams = field(default_factory=PoseGraphParams)
    max_range: float = 40.0
    voxel: float = 0.05
    motion_filter_distance: float = 0.2
    motion_filter_angle: float = math.radians(10.0)
    match_filtered_scans: bool = False
    loop_every: int = 1
    loop_search_distance: float = 10.0
    loop_skip_submaps: int = 1
    loop_max_candidates: int = 4
    loop_resample_distance: float = 3.0
    loop_constrained_distance: float = 6.0
    optimize_every: int = 20
    map_resolution: float = 0.05
    refine_rounds: int = 2
    refine_resolution: float = 0.025
    refine_sigma: float = 0.04
    refine_max_cells: int = 8_000_000
    refine_degeneracy_threshold: float = 0.002
    refine_max_correction: tuple[float, float] = (0.25, math.radians(3.0))
    map_clamp: bool = False
    map_error: bool = True
    table_cache_mb: float = 16.0

    def __post_init__(self) -> None:
        check_positive(self.max_range, "SlamParams.max_range")
        check_positive(self.voxel, "SlamParams.voxel", allow_zero=True)
        check_positive(self.loop_search_distance, "SlamParams.loop_search_distance")
        check_positive(self.retry_margin, "SlamParams.retry_margin", allow_zero=True)
        check_positive(self.window_sigmas, "SlamParams.window_sigmas")
        check_positive(self.min_linear_window, "SlamParams.min_linear_window", allow_zero=True)
        check_positive(self.min_angular_window, "SlamParams.min_angular_window", allow_zero=True)
        check_positive(self.min_match_sigma, "SlamParams.min_match_sigma")
        check_positive(self.min_match_rot, "SlamParams.min_match_rot")
        check_positive(
            self.min_surface_fraction, "SlamParams.min_surface_fraction", allow_zero=True
        )
        check_positive(self.table_cache_mb, "SlamParams.table_cache_mb")
        check_positive(
            self.motion_filter_distance, "SlamParams.motion_filter_distance", allow_zero=True
        )
        check_positive(self.motion_filter_angle, "SlamParams.motion_filter_angle", allow_zero=True)
        check_positive(self.map_resolution, "SlamParams.map_resolution")
        check_positive(self.refine_resolution, "SlamParams.refine_resolution")
        check_positive(self.refine_sigma, "SlamParams.refine_sigma")
        for k, v in enumerate(self.refine_max_correction):
            check_positive(v, f"SlamParams.refine_max_correction[{k}]")
        for name in ("refine_rounds", "refine_max_cells"):
            v = getattr(self, name)
            if int(v) != v or v < 0:
                raise ConfigurationError(f"SlamParams.{name}: expected an integer >= 0, got {v}")
        check_positive(
            self.loop_resample_distance, "SlamParams.loop_resample_distance", allow_zero=True
        )
        check_positive(
            self.loop_constrained_distance, "SlamParams.loop_constrained_distance", allow_zero=True
        )
        for k, v in enumerate(self.max_retry_window):
            check_positive(v, f"SlamParams.max_retry_window[{k}]")
        for k, v in enumerate(self.max_loop_window):
            check_positive(v, f"SlamParams.max_loop_window[{k}]")
        for k, v in enumerate(self.loop_ambiguity_radius):
            check_positive(v, f"SlamParams.loop_ambiguity_radius[{k}]", allow_zero=True)
        if not 0.0 < self.refine_degeneracy_threshold < 1.0:
            raise ConfigurationError(
                "SlamParams.refine_degeneracy_threshold: expected a value in (0, 1), got"
                f" {self.refine_degeneracy_threshold}"
            )
        if not 0.0 < self.degeneracy_threshold < 1.0:
            raise ConfigurationError(
                "SlamParams.degeneracy_threshold: expected a value in (0, 1), got"
                f" {self.degeneracy_threshold}"
            )
        if not 0.0 <= self.retry_below <= 1.0:
            raise ConfigurationError(
                f"SlamParams.retry_below: expected a value in [0, 1], got {self.retry_below}"
            )
        check_positive(self.match_gate_chi2, "SlamParams.match_gate_chi2")
        for name in ("retry_relative", "unusable_relative", "loop_score_relative"):
            v = getattr(self, name)
            if not 0.0 < v <= 1.0:
                raise ConfigurationError(f"SlamParams.{name}: expected a value in (0, 1], got {v}")
        check_positive(self.loop_score_floor, "SlamParams.loop_score_floor")
        if int(self.gate_recovery) != self.gate_recovery or self.gate_recovery < 0:
            raise ConfigurationError(
                f"SlamParams.gate_recovery: expected an integer >= 0, got {self.gate_recovery}"
            )
        for name in ("loop_every", "optimize_every", "loop_max_candidates", "min_submap_scans"):
            v = getattr(self, name)
            if int(v) != v or v < 1:
                raise ConfigurationError(f"SlamParams.{name}: expected an integer >= 1, got {v}")
        if int(self.loop_skip_submaps) != self.loop_skip_submaps or self.loop_skip_submaps < 0:
            raise ConfigurationError(
                f"SlamParams.loop_skip_submaps: expected an integer >= 0, got"
                f" {self.loop_skip_submaps}"
            )

    @property
    def loop_min_score(self) -> float:
        """Minimum loop-closure match score (``loop.min_score``)."""
        return self.loop.min_score


@dataclass(frozen=True, eq=False)
class SlamResult:
    """Output of :func:`run_slam`.

    Attributes
    ----------
    poses : ndarray of shape (N, 3)
        Optimised global sensor pose of every scan.
    local_poses : ndarray of shape (N, 3)
        Front-end (scan matching fused with odometry) poses.
    grid : OccupancyGrid
        Map from all scans at the optimised poses.
    loop_closures : list of (submap, scan index)
        Accepted loop constraints (in the final graph).
    n_submaps : int
    node_scans : ndarray of shape (K,)
        Scan index of each graph node (the scans kept by the motion filter).
    match_scores : ndarray of shape (N,)
        Local match score per scan (0 when not matched).
    timings : dict of str to float
        Wall-clock seconds spent in ``frontend``, ``loop_search``, ``optimize``, ``map`` and
        ``total``; ``total_cpu`` is the process CPU time [s] (all threads), the fair measure
        on a shared machine.
    n_optimizations : int
    n_retries : int
        Scans whose real-time match was retried with the wide window.
    graph : PoseGraph or None
        The final pose graph (factors and optimised values).
    n_loop_searches : int
        Loop-closure scan matches run (node, submap pairs searched).
    rejected_loops : list of (submap, scan index, reason)
        Loop-closure candidates that matched but were not accepted, with the test they failed
        (``ambiguous``, ``degenerate``, ``inconsistent``, ``residual``).
    warnings : list of str
        Why the result may be doubtful (empty when nothing was found); also written into the
        map's metadata by ``symloc map build``.
    degenerate_scans : ndarray of shape (N,)
        Directions the scan's match left unconstrained (0-3; -1 when not matched).
    odometry_model : dict
        What was learnt about the odometry (calibration, noise, matcher error).
    match_poses : ndarray of shape (N, 3)
        Pose of each matched scan as its match alone put it, in the local frame (NaN when
        not matched).
    gated_scans : ndarray of shape (N,)
        Scans whose match the odometry gate refused (they followed the odometry).
    map_error : MapError or None
        The map's own error estimated from its node scans (:mod:`symloc.slam.map_error`;
        None when not estimated); :attr:`grid` was already moved by its ``shift``.
    map_error_field : MapErrorField or None
        The map's position error place by place, from the pose graph's marginals
        (:mod:`symloc.slam.pose_marginals`; in :attr:`grid`'s frame); None when not estimated.
    """

    poses: FloatArray
    local_poses: FloatArray
    grid: OccupancyGrid
    loop_closures: list[tuple[int, int]]
    n_submaps: int
    node_scans: NDArray[np.intp]
    match_scores: FloatArray
    timings: dict[str, float]
    n_optimizations: int
    n_retries: int = 0
    graph: PoseGraph | None = None
    n_loop_searches: int = 0
    rejected_loops: list[tuple[int, int, str]] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    degenerate_scans: NDArray[np.intp] = field(default_factory=lambda: np.zeros(0, np.intp))
    odometry_model: dict[str, float | bool | int] = field(default_factory=dict)
    match_poses: FloatArray = field(default_factory=lambda: np.zeros((0, 3)))
    gated_scans: NDArray[np.bool_] = field(default_factory=lambda: np.zeros(0, bool))
    map_error: MapError | None = None
    map_error_field: MapErrorField | None = None

    @property
    def doubtful(self) -> bool:
        """True when :attr:`warnings` is not empty."""
        return bool(self.warnings)

    def map_metadata(self) -> dict[str, object]:
        """What a saved map should carry about how it was made (``symloc_slam`` YAML key)."""
        s = self.summary()
        keep = ("scans", "nodes", "loops_accepted", "loops_rejected", "degenerate_fraction")
        meta: dict[str, object] = {k: s[k] for k in keep}
        meta["doubtful"] = self.doubtful
        meta["warnings"] = list(self.warnings)
        error: dict[str, object] = {}
        if self.map_error is not None:
            error.update(self.map_error.as_dict())
        if self.map_error_field is not None:
            error["field"] = self.map_error_field.rows()
        if error:
            meta["map_error"] = error
        return {"symloc_slam": meta}

    def summary(self) -> dict[str, object]:
        """Plain numbers (JSON-ready): sizes, loop closures, CPU time, warnings."""
        reasons: dict[str, int] = {}
        for _, _, why in self.rejected_loops:
            reasons[why] = reasons.get(why, 0) + 1
        matched = self.degenerate_scans[self.degenerate_scans >= 0]
        return {
            "scans": int(self.poses.shape[0]),
            "nodes": int(self.node_scans.size),
            "submaps": int(self.n_submaps),
            "loops_accepted": len(self.loop_closures),
            "loops_rejected": len(self.rejected_loops),
            "loops_rejected_by_reason": reasons,
            "loop_searches": int(self.n_loop_searches),
            "retries": int(self.n_retries),
            "degenerate_fraction": float(np.mean(matched > 0)) if matched.size else 0.0,
            "gated": int(self.gated_scans.sum()),
            "slam_cpu_s": float(self.timings.get("total_cpu", float("nan"))),
            "timings_s": {k: float(v) for k, v in self.timings.items()},
            "odometry_model": dict(self.odometry_model),
            "doubtful": self.doubtful,
            "warnings": list(self.warnings),
            "map_error": None if self.map_error is None else self.map_error.as_dict(),
        }


def scan_points(scan: LaserScan, max_range: float, voxel: float) -> FloatArray:
    """End points ``(M, 2)`` [m] of ``scan`` within ``max_range``, thinned to one per voxel."""
    sp = scan.to_points()
    pts = sp.points[sp.ranges <= max_range]
    if voxel > 0 and pts.shape[0] > 1:
        keys = np.floor(pts / voxel).astype(np.int64)
        _, first = np.unique(keys[:, 0] * 2_000_003 + keys[:, 1], return_index=True)
        pts = pts[np.sort(first)]
    return pts


class _TableCache:
    """Keeps the likelihood tables of the most recently matched submaps within a byte budget."""

    def __init__(self, budget_mb: float) -> None:
        self.budget = int(budget_mb * 1024 * 1024)
        self.order: OrderedDict[int, Submap] = OrderedDict()

    def touch(self, sm: Submap) -> None:
        """``sm`` is about to be matched: newest; drop the oldest tables over the budget."""
        self.order.pop(sm.index, None)
        self.order[sm.index] = sm
        total = sum(s.nbytes for s in self.order.values() if s.has_table)
        while total > self.budget and len(self.order) > 1:
            _, old = self.order.popitem(last=False)
            if old.has_table:
                total -= old.nbytes
                old.release_table()


def _rotate_cov(cov: FloatArray, theta: float) -> FloatArray:
    """Covariance (3, 3) of x, y, theta expressed in a frame rotated by ``theta``."""
    c, s = math.cos(theta), math.sin(theta)
    j = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return np.asarray(j @ cov @ j.T, dtype=np.float64)


def _propagate(
    cov: FloatArray, start: FloatArray, increment: FloatArray, inc_cov: FloatArray
) -> FloatArray:
    """Covariance (3, 3) of ``start + increment`` (world frame) from both covariances."""
    end = compose(start, increment)
    jx = np.array(
        [[1.0, 0.0, -(end[1] - start[1])], [0.0, 1.0, end[0] - start[0]], [0.0, 0.0, 1.0]]
    )
    return np.asarray(jx @ cov @ jx.T + _rotate_cov(inc_cov, float(start[2])), dtype=np.float64)


def _in_body(cov_in_parent: FloatArray, pose_in_parent: FloatArray) -> FloatArray:
    """A covariance of ``pose`` expressed in the parent frame, re-expressed in the pose's frame."""
    return _rotate_cov(cov_in_parent, -float(pose_in_parent[2]))


_UNMATCHED_COV = np.diag([UNCONSTRAINED_SIGMA**2] * 2 + [UNCONSTRAINED_SIGMA**2])


class _Run:
    """State of one :func:`run_slam` call (split out of it to keep each step readable)."""

    def __init__(self, scans: Sequence[LaserScan], odom: FloatArray, prm: SlamParams) -> None:
        self.scans = scans
        self.odom = odom
        self.prm = prm
        n = len(scans)
        self.n = n
        self.active = ActiveSubmaps(prm.submap)
        self.graph = PoseGraph(prm.graph)
        self.cache = _TableCache(prm.table_cache_mb)
        self.model = OdometryModel(prm.odometry)
        self.verifier = LoopVerifier(prm.loop)
        self.local = np.zeros((n, 3))
        self.match_pose = np.full((n, 3), np.nan)
        self.scores = np.zeros(n)
        self.degenerate = np.full(n, -1, dtype=np.intp)
        self.cov = np.zeros((3, 3))  # of local[i] relative to the matching submap
        self.gate_cov = np.zeros((3, 3))  # the same with the generous odometry model
        self.global_from_local = np.zeros(3)
        self.node_scans: list[int] = []
        self.node_constraint: list[MatchConstraint | None] = []
        self.match_cov = np.zeros((n, 3, 3))  # of each match, in the local frame
        self._constraint_cache: tuple[int, MatchConstraint | None] = (-1, None)
        self.recent_scores: deque[float] = deque(maxlen=50)
        self.poor = np.zeros(n, dtype=bool)
        self.gated = np.zeros(n, dtype=bool)
        self.n_gated = 0  # consecutive matches the gate refused
        self.pending_loops = 0
        self.n_opt = 0
        self.n_retries = 0
        self.n_loop_searches = 0
        self.travel = 0.0
        self.travel_at_loop = 0.0
        self.next_search: dict[int, float] = {}
        self.submap_centres: dict[int, FloatArray] = {}
        self.timings = {"frontend": 0.0, "loop_search": 0.0, "optimize": 0.0, "map": 0.0}

    # -- front end -------------------------------------------------------------------------
    def _is_node(self, i: int, pose: FloatArray) -> bool:
        if not self.node_scans or i == self.n - 1:
            return True
        moved = relative(self.local[self.node_scans[-1]], pose)
        return (
            float(np.hypot(moved[0], moved[1])) >= self.prm.motion_filter_distance
            or abs(float(moved[2])) >= self.prm.motion_filter_angle
        )

    def typical_score(self) -> float | None:
        """Median score of the last 50 real-time matches (None before 10)."""
        if len(self.recent_scores) < 10:
            return None
        return float(np.median(self.recent_scores))

    def poor_score(self) -> float:
        """Match score below which a match is retried (see ``SlamParams.retry_below``)."""
        med = self.typical_score()
        if med is None:
            return self.prm.retry_below
        return min(self.prm.retry_below, self.prm.retry_relative * med)

    def unusable_score(self) -> float:
        """Match score below which a match is not used (see ``SlamParams.unusable_relative``)."""
        med = self.typical_score()
        cap = self.prm.unusable_relative * self.prm.retry_below / self.prm.retry_relative
        if med is None:
            return cap
        return min(cap, self.prm.unusable_relative * med)

    def loop_min_score(self) -> float:
        """Loop-closure score threshold: ``loop.min_score`` or relative to the run's scores."""
        med = self.typical_score()
        if med is None:
            return self.prm.loop.min_score
        return max(
            self.prm.loop_score_floor,
            min(self.prm.loop.min_score, self.prm.loop_score_relative * med),
        )

    def _match_sigmas(self) -> tuple[float, float]:
        st, sr = self.model.matcher_sigmas
        return max(st, self.prm.min_match_sigma), max(sr, self.prm.min_match_rot)

    def _constraint(self, i: int, pts: FloatArray) -> MatchConstraint:
        """What a match of scan ``i`` (points ``pts``) can constrain (its own geometry)."""
        if self._constraint_cache[0] != i:
            info, _ = scan_information(pts)
            st, sr = self._match_sigmas()
            mc = analyse_match(
                info,
                pts,
                st,
                sigma_rot=sr,
                threshold=self.prm.degeneracy_threshold,
                min_strength=self.prm.min_surface_fraction,
            )
            self._constraint_cache = (i, mc)
        cached = self._constraint_cache[1]
        assert cached is not None
        return cached

    def front_end(self, i: int, pts: FloatArray) -> MatchConstraint | None:
        """Pose of scan ``i`` in the local frame; returns its match constraint (None: none)."""
        prm = self.prm
        if i == 0:
            self.local[0] = self.odom[0]
            return None
        inc = self.model.correct(relative(self.odom[i - 1], self.odom[i]))
        pred = compose(self.local[i - 1], inc)
        pred_cov = _propagate(self.cov, self.local[i - 1], inc, self.model.covariance(inc))
        self.gate_cov = _propagate(
            self.gate_cov, self.local[i - 1], inc, self.model.generous_covariance(inc)
        )
        target = self.active.matching_submap
        if (
            (not prm.match_filtered_scans and not self._is_node(i, pred))
            or target is None
            or target.n_scans < prm.min_submap_scans
            or pts.shape[0] < 10
        ):
            self.local[i] = pred
            self.cov = pred_cov
            return None
        self.cache.touch(target)
        table = target.table()
        init = relative(target.local_pose, pred)
        theta_s = float(target.local_pose[2])
        cov_s = _rotate_cov(pred_cov, -theta_s)
        sig_t = math.sqrt(max(cov_s[0, 0], cov_s[1, 1]))
        sig_r = math.sqrt(cov_s[2, 2])
        k = prm.window_sigmas
        csm = dataclasses.replace(
            prm.local_csm,
            linear_window=min(max(k * sig_t, prm.min_linear_window), prm.local_csm.linear_window),
            angular_window=min(
                max(k * sig_r, prm.min_angular_window), prm.local_csm.angular_window
            ),
        )
        res = match_scan(table, pts, init, csm)
        poor = self.poor_score()
        if res.score < poor:
            retry = dataclasses.replace(
                prm.retry_csm,
                linear_window=min(
                    max(prm.retry_csm.linear_window, 2.0 * csm.linear_window),
                    prm.max_retry_window[0],
                ),
                angular_window=min(
                    max(prm.retry_csm.angular_window, 2.0 * csm.angular_window),
                    prm.max_retry_window[1],
                ),
            )
            wide = match_scan(table, pts, init, retry)
            self.n_retries += 1
            if wide.score >= self.unusable_score() and wide.score > res.score + prm.retry_margin:
                res = wide
        mc = self._constraint(i, pts)
        self.scores[i] = res.score
        self.poor[i] = res.score < self.unusable_score()
        self.recent_scores.append(res.score)
        self.degenerate[i] = mc.n_degenerate
        self.match_pose[i] = compose(target.local_pose, res.pose)
        # the gate: a match the prediction cannot explain is not trusted at once
        innov = res.pose - init
        innov[2] = math.remainder(float(innov[2]), 2.0 * math.pi)
        gate_s = _rotate_cov(self.gate_cov, -theta_s)
        d2 = float(innov @ np.linalg.solve(gate_s + mc.covariance, innov))
        typical = self.typical_score()
        # a match that explains the scan as well as matches usually do is believed even
        # against the odometry (wheels slip); a worse one must agree with it
        gated = d2 > prm.match_gate_chi2 and (typical is None or res.score < typical)
        self.gated[i] = gated
        if self.poor[i] or (gated and self.n_gated < prm.gate_recovery):
            self.n_gated += int(gated)
            self.local[i] = pred
            self.cov = pred_cov
            unmatched = MatchConstraint(
                covariance=_UNMATCHED_COV.copy(),
                strengths=mc.strengths,
                directions=mc.directions,
                n_degenerate=3,
                length=mc.length,
            )
            self.match_cov[i] = _UNMATCHED_COV
            return unmatched
        if gated or not prm.fuse_odometry:
            # the matches kept disagreeing (the odometry was wrong), or no fusion: the match
            # decides every direction it constrains
            cov_s = cov_s + np.eye(3) * 1.0e2
        self.n_gated = 0
        # the match's covariance comes from the scan's own points (the body frame): into the
        # submap frame with the matched heading (a turn inside a submap must not rotate a
        # corridor's free axis, or a round room's coupled turn-and-slide, into another one)
        mc_cov_s = _rotate_cov(mc.covariance, float(res.pose[2]))
        fused, post = fuse(init, cov_s, res.pose, mc_cov_s)
        self.local[i] = compose(target.local_pose, fused)
        self.cov = _rotate_cov(post, theta_s)
        self.gate_cov = self.cov.copy()
        self.match_cov[i] = _rotate_cov(mc_cov_s, theta_s)
        return mc

    def add_node(self, i: int, mc: MatchConstraint | None) -> int:
        """Insert scan ``i`` as a graph node; returns the node index."""
        k = len(self.node_scans)
        self.node_scans.append(i)
        self.node_constraint.append(mc)
        n_before = len(self.active.submaps)
        touched = self.active.insert(k, self.local[i], self.scans[i])
        self.graph.add_node(k, compose(self.global_from_local, self.local[i]))
        for sm in self.active.submaps[n_before:]:
            self.graph.add_submap(sm.index, compose(self.global_from_local, sm.local_pose))
        for sm in touched:
            z = sm.node_poses[-1]
            if mc is None:
                cov = _UNMATCHED_COV if sm.n_scans > 1 else None
            else:
                # the match covariance, from the local frame into the node's frame
                cov = _in_body(self.match_cov[i], self.local[i])
            self.graph.add_intra(sm.index, k, z, cov)
        if k > 0:
            prev = self.node_scans[-2]
            raw = relative(self.odom[prev], self.odom[i])
            inc = self.model.correct(raw)
            self.graph.add_odometry(k - 1, k, inc, self.model.covariance(inc))
            self.travel += float(np.hypot(*(self.local[i, :2] - self.local[prev, :2])))
        good = mc is not None and not self.poor[i] and self.degenerate[i] == 0
        self.model.add_node(self.odom[i], self.match_pose[i] if good else None)
        return k

    # -- loop closure ----------------------------------------------------------------------
    def loop_search(self, i: int, k: int, pts: FloatArray) -> None:
        """Search, verify and add loop closures of node ``k`` (scan ``i``)."""
        prm = self.prm
        if k % prm.loop_every != 0 or pts.shape[0] < 10:
            return
        finished = [s for s in self.active.submaps if s.finished and k not in s.nodes]
        if prm.loop_skip_submaps:
            finished = finished[: -prm.loop_skip_submaps]
        if not finished:
            return
        node_g = compose(self.global_from_local, self.local[i])
        since = self.travel - self.travel_at_loop
        dt, dr = self.verifier.drift_rates()
        csm = dataclasses.replace(
            prm.loop_csm,
            linear_window=min(prm.loop_csm.linear_window + dt * since, prm.max_loop_window[0]),
            angular_window=min(prm.loop_csm.angular_window + dr * since, prm.max_loop_window[1]),
        )
        candidates = []
        for sm in finished:
            if sm.index not in self.submap_centres:
                self.submap_centres[sm.index] = np.mean(np.array(sm.node_poses)[:, :2], axis=0)
            init = relative(self.graph.submap_pose(sm.index), node_g)
            dist = float(np.hypot(*(init[:2] - self.submap_centres[sm.index])))
            if dist <= prm.loop_search_distance:
                candidates.append((dist, sm.index, init))
        candidates.sort(key=lambda c: c[0])
        min_score = self.loop_min_score()
        for _, j, init in candidates[: prm.loop_max_candidates]:
            if self.travel < self.next_search.get(j, -math.inf):
                continue  # sampled: searched (or constrained) too recently
            sm = self.active.submaps[j]
            self.cache.touch(sm)
            table = sm.table()
            res = match_scan(table, pts, init, csm, runner_up_exclusion=prm.loop_ambiguity_radius)
            self.n_loop_searches += 1
            found = False
            if res.score >= min_score:
                mc = self._constraint(i, pts)
                cand = LoopCandidate(
                    submap=j,
                    node=k,
                    measurement=res.pose,
                    covariance=mc.covariance,  # body frame, as the graph's factor wants
                    score=res.score,
                    runner_up=res.runner_up_score,
                    degenerate=mc.degenerate,
                    correction=relative(init, res.pose),
                    travel=self.travel,
                    since_loop=since,
                )
                accepted = self.verifier.submit(cand, k, min_score=min_score)
                for c in accepted:
                    self.graph.add_loop(c.submap, c.node, c.measurement, c.covariance)
                    self.pending_loops += 1
                    self.travel_at_loop = self.travel
                found = bool(accepted)
            wait = prm.loop_constrained_distance if found else prm.loop_resample_distance
            self.next_search[j] = self.travel + wait

    # -- final refinement ------------------------------------------------------------------
    def _node_points(self) -> Iterator[FloatArray]:
        prm = self.prm
        for i in self.node_scans:
            yield scan_points(self.scans[i], prm.max_range, prm.voxel)

    def refine_to_map(self) -> bool:
        """The final scan-to-map refinement (``refine_rounds`` rounds); False when the map
        is too large to refine."""
        prm = self.prm
        graph = self.graph
        priors: list[int] = []
        max_t, max_r = prm.refine_max_correction
        for _ in range(prm.refine_rounds):
            poses = graph.node_poses()

            def point_sets(p: FloatArray = poses) -> Iterator[FloatArray]:
                return nodes_in_map(p, self._node_points())

            table = density_table(
                point_sets,
                prm.refine_resolution,
                prm.refine_sigma,
                max_cells=prm.refine_max_cells,
            )
            if table is None:
                return False
            graph.remove_factors(priors)
            priors = []
            for k, pts in enumerate(self._node_points()):
                if pts.shape[0] < 10:
                    continue
                refined = refine_pose(table, pts, poses[k])
                step = relative(poses[k], refined)
                if math.hypot(step[0], step[1]) > max_t or abs(step[2]) > max_r:
                    continue
                # the scan's own information, with a far lower degeneracy threshold than the
                # front end's: a direction a few end points constrain (a corridor's end wall
                # seen from afar) gets a weak but finite weight, and the many nodes that see it
                # fix it together
                info, _ = scan_information(pts)
                st, sr = self._match_sigmas()
                mc = analyse_match(
                    info,
                    pts,
                    st,
                    sigma_rot=sr,
                    threshold=prm.refine_degeneracy_threshold,
                    min_strength=prm.min_surface_fraction,
                )
                if mc.n_degenerate == 3:
                    continue
                # for the map's error estimate the prior counts only in the directions the
                # front end would trust: a far end wall seen by hundreds of nodes is one wall
                marginal = analyse_match(
                    info,
                    pts,
                    st,
                    sigma_rot=sr,
                    threshold=prm.degeneracy_threshold,
                    min_strength=prm.min_surface_fraction,
                )
                priors.append(
                    graph.add_map_prior(
                        k, refined, mc.covariance, marginal_covariance=marginal.covariance
                    )
                )
            graph.optimize()
            self.n_opt += 1
            moved = graph.node_poses() - poses
            _LOG.debug(
                "scan-to-map refinement: %d of %d nodes matched, nodes moved by median %.4f m,"
                " max %.4f m",
                len(priors),
                len(poses),
                float(np.median(np.hypot(moved[:, 0], moved[:, 1]))),
                float(np.max(np.hypot(moved[:, 0], moved[:, 1]))),
            )
        return True

    def optimize(self, i: int, k: int) -> None:
        """Optimise, drop the loops the graph disagrees with, re-anchor the local frame."""
        self.graph.optimize()
        self.n_opt += 1
        self.graph.check_loops()
        self.pending_loops = 0
        self.global_from_local = compose(self.graph.node_pose(k), inverse(self.local[i]))


def _warnings(run: _Run, rejected: list[tuple[int, int, str]]) -> list[str]:
    """Why the result may be doubtful (see :attr:`SlamResult.warnings`)."""
    out: list[str] = []
    matched = run.degenerate[run.degenerate >= 0]
    if matched.size:
        frac = float(np.mean(matched > 0))
        if frac > 0.25:
            out.append(
                f"{100 * frac:.0f} % of the matched scans left a direction unconstrained"
                " (corridors, open space, few returns): positions there follow the odometry"
            )
        low = float(np.mean(run.poor[run.degenerate >= 0]))
        if low > 0.1:
            out.append(
                f"{100 * low:.0f} % of the scans matched their submap too poorly to be used"
                f" (score below {run.unusable_score():.2f}): they followed the odometry"
            )
    n_acc = len(run.graph.loops)
    by_reason: dict[str, int] = {}
    for _, _, why in rejected:
        by_reason[why] = by_reason.get(why, 0) + 1
    gated = int(run.gated.sum())
    if gated > 0.05 * max(len(run.node_scans), 1):
        out.append(
            f"{gated} scan matches disagreed with the odometry beyond its learnt noise"
            " (the gate refused them)"
        )
    if n_acc == 0 and rejected:
        out.append(f"no loop closure accepted, {len(rejected)} rejected: drift is not corrected")
    if by_reason.get("residual", 0):
        out.append(
            f"{by_reason['residual']} loop closures disagreed with the optimised graph and were"
            " removed"
        )
    if n_acc and by_reason.get("inconsistent", 0) > n_acc:
        out.append(
            f"more unconfirmed loop candidates ({by_reason['inconsistent']}) than accepted"
            f" closures ({n_acc}): look-alike places"
        )
    return out


#: Grid [rad] that SLAM's odometry headings are rounded to (2^-30 rad, about 1e-9 rad): far
#: below any odometry's error, far above the 5e-16 rad that a heading moves when it goes
#: through a quaternion (a nav_msgs/Odometry in a bag) and back.
ODOMETRY_HEADING_STEP = 2.0**-30


def slam_input(
    scans: Sequence[LaserScan], odometry: ArrayLike
) -> tuple[list[LaserScan], FloatArray]:
    """SLAM's input as :func:`run_slam` takes it, whatever the odometry came from.

    A CARMEN log read as text and the same log written to a ROS bag and read back must give
    SLAM one input: SLAM's loop-closure decisions turn on perturbations far below any sensor's
    error (issue 28: on acapulco the ATE went from 0.158 m to 0.250 m when the scans were
    rounded to float32, and csail's tipped again on headings 5e-16 rad apart). The scans are
    taken as given: a log's reader gives them at sensor_msgs/LaserScan's float32 precision, as a
    bag does (:func:`symloc.scan.message_precision`, :func:`symloc.io.carmen.read_carmen`). The
    odometry headings are wrapped to (-pi, pi] (a quaternion does) and rounded to a grid of
    :data:`ODOMETRY_HEADING_STEP` rad: a heading read back from the quaternion of a
    nav_msgs/Odometry differs from the one written by up to 5e-16 rad, and the two round to the
    same grid value unless they straddle a grid boundary (a chance of about 1e-6 per heading).
    Positions are kept (nav_msgs carries them as float64). SLAM reads only the odometry's
    increments, wrapped, so this moves what it reads by at most 1e-9 rad.

    Parameters
    ----------
    scans : sequence of LaserScan
        N scans, ranges [m] and angles [rad]; returned as a list, unchanged.
    odometry : array of shape (N, 3)
        x [m], y [m], theta [rad] at each scan.

    Returns
    -------
    scans : list of LaserScan
    odometry : ndarray of shape (N, 3)
        A copy, its headings [rad] wrapped and on the grid.
    """
    odom = np.array(check_array(odometry, "odometry", shape=(None, 3)), dtype=np.float64)
    step = ODOMETRY_HEADING_STEP
    odom[:, 2] = np.round(np.asarray(wrap_angle(odom[:, 2])) / step) * step
    return list(scans), odom


def run_slam(
    scans: Sequence[LaserScan],
    odometry: ArrayLike,
    params: SlamParams | None = None,
    *,
    progress: bool = True,
    desc: str = "slam",
) -> SlamResult:
    """Run laser SLAM over ``scans`` with odometry poses ``odometry`` (N, 3).

    Parameters
    ----------
    scans : sequence of LaserScan
        In time order; the sensor frame is the robot frame.
    odometry : array of shape (N, 3)
        Odometry pose at each scan (only increments are used; the first one fixes the map
        frame); headings rounded to :data:`ODOMETRY_HEADING_STEP` (:func:`slam_input`).
    params : SlamParams, optional
    progress : bool
        Show a tqdm bar on stderr.

    Returns
    -------
    SlamResult
    """
    prm = params if params is not None else SlamParams()
    odom = check_array(odometry, "odometry", shape=(None, 3))
    n = len(scans)
    if n == 0 or odom.shape[0] != n:
        raise ConfigurationError(f"odometry: expected one pose per scan ({n}), got {odom.shape[0]}")
    scans, odom = slam_input(scans, odom)
    t_start = time.perf_counter()
    cpu_start = time.process_time()
    run = _Run(scans, odom, prm)
    timings = run.timings
    bar = tqdm(total=n, desc=desc, unit="scan", disable=not progress, leave=False)
    for i in range(n):
        t0 = time.perf_counter()
        pts = scan_points(scans[i], prm.max_range, prm.voxel)
        mc = run.front_end(i, pts)
        if not run._is_node(i, run.local[i]):
            timings["frontend"] += time.perf_counter() - t0
            bar.update(1)
            continue
        k = run.add_node(i, mc)
        timings["frontend"] += time.perf_counter() - t0
        t1 = time.perf_counter()
        run.loop_search(i, k, pts)
        timings["loop_search"] += time.perf_counter() - t1
        if run.pending_loops and (k + 1) % prm.optimize_every == 0:
            t2 = time.perf_counter()
            run.optimize(i, k)
            timings["optimize"] += time.perf_counter() - t2
        bar.update(1)
    bar.close()
    t2 = time.perf_counter()
    run.verifier.finish()
    run.optimize(run.node_scans[-1], len(run.node_scans) - 1)
    timings["optimize"] += time.perf_counter() - t2
    # the submaps (two active grids) and their cached tables are done with: free them before
    # the refinement's density grid and the final map
    n_submaps = len(run.active.submaps)
    run.active.submaps.clear()
    run.cache.order.clear()
    t_ref = time.perf_counter()
    if not run.refine_to_map():
        _LOG.warning(
            "the map is larger than %d cells of %g m: no final scan-to-map refinement",
            prm.refine_max_cells,
            prm.refine_resolution,
        )
    timings["refine"] = time.perf_counter() - t_ref
    t2 = time.perf_counter()
    graph = run.graph
    node_poses = graph.node_poses()
    nodes = np.array(run.node_scans, dtype=np.intp)
    # every scan follows its last node: node pose composed with the front-end motion since it
    owner = np.searchsorted(nodes, np.arange(n), side="right") - 1
    local = run.local
    poses = compose(node_poses[owner], relative(local[nodes[owner]], local))
    timings["optimize"] += time.perf_counter() - t2

    t3 = time.perf_counter()
    model = InverseSensorModel(
        p_hit=prm.submap.model.p_hit,
        p_miss=prm.submap.model.p_miss,
        p_min=prm.submap.model.p_min,
        p_max=prm.submap.model.p_max,
        max_range=prm.max_range,
        no_return_range=prm.submap.model.no_return_range,
    )
    grid = LogOddsGrid(prm.map_resolution, model, poses[0, :2], clamp=prm.map_clamp)
    grid.reserve(poses, scans)  # one allocation, not a copy per growth step
    for i in range(n):
        grid.integrate(poses[i], scans[i])
    occ = grid.to_occupancy_grid(crop_margin=10)
    del grid  # the log-odds (4 bytes a cell) are not needed past the occupancy grid
    timings["map"] = time.perf_counter() - t3
    map_error = None
    if prm.map_error and occ.data.size <= prm.refine_max_cells:
        t4 = time.perf_counter()
        # imported here: the map error aligns scans as the localizer does (numba kernels,
        # OpenCV, scikit-image, ~90 MB), which the rest of SLAM does not need
        from symloc.slam.map_error import estimate_map_error

        map_error = estimate_map_error(occ, [scans[int(i)] for i in nodes], poses[nodes])
        if map_error is not None:
            origin = np.asarray(occ.origin, dtype=np.float64).copy()
            origin[:2] -= map_error.shift
            occ = dataclasses.replace(occ, origin=origin)
            _LOG.info(
                "map error: std %.3f m (p95 %.3f m over %d nodes); map moved by %s m",
                map_error.std_xy,
                map_error.p95_xy,
                map_error.nodes,
                np.round(-map_error.shift, 4),
            )
        timings["map_error"] = time.perf_counter() - t4
    field = None
    if prm.map_error:
        t5 = time.perf_counter()
        shift = None if map_error is None else map_error.shift
        field = map_error_field(graph, shift=shift)
        timings["map_error_field"] = time.perf_counter() - t5
    timings["total"] = time.perf_counter() - t_start
    timings["total_cpu"] = time.process_time() - cpu_start
    rejected = [(c.submap, int(nodes[c.node]), c.reason) for c in run.verifier.rejected]
    rejected += [(j, int(nodes[k]), "residual") for j, k, _ in graph.removed_loops]
    return SlamResult(
        poses=poses,
        local_poses=local,
        grid=occ,
        loop_closures=[(j, int(nodes[k])) for j, k in graph.loops],
        n_submaps=n_submaps,
        node_scans=nodes,
        match_scores=run.scores,
        timings=timings,
        n_optimizations=run.n_opt,
        n_retries=run.n_retries,
        n_loop_searches=run.n_loop_searches,
        graph=graph,
        rejected_loops=rejected,
        warnings=_warnings(run, rejected),
        degenerate_scans=run.degenerate,
        odometry_model=run.model.summary(),
        match_poses=run.match_pose,
        gated_scans=run.gated,
        map_error=map_error,
        map_error_field=field,
    )
