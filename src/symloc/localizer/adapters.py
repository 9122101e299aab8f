"""Adapters from the real parts (AMCL, Algorithm 1, the occupancy grid) to the localizer's Protocols.

- :class:`AmclTracker` wraps :class:`symloc.mcl.Amcl` and its
  :class:`~symloc.mcl.confidence.ConfidenceJudge` (the verdict, judged after each filter
  update) and returns a :class:`~symloc.localizer.types.TrackerResult`.
- :class:`ReportJudge` wraps :func:`symloc.symmetry.judge_symmetry` (or any function returning a
  report with ``symmetric, order, kind, center, corners, gv_distance, reason``) and adds the
  bearing of the middle between two adjacent corners that Algorithm 2 faces.
- :class:`GridScorer` scores poses against an occupancy grid with a likelihood field (the
  test whether rotated copies of AMCL's estimate explain the scan as well).
- :class:`GlobalSearchProposer` wraps :class:`symloc.mcl.global_search.GlobalSearch` as a
  :class:`~symloc.localizer.types.PoseProposer` (the laser's proposals from one scan).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc._checks import check_positive
from symloc.errors import ConfigurationError
from symloc.geometry import compose, wrap_angle
from symloc.grid import OccupancyGrid
from symloc.grid.fields import MapFields
from symloc.mcl.amcl import Amcl, AmclResult
from symloc.mcl.confidence import Confidence, ConfidenceConfig, ConfidenceJudge
from symloc.mcl.global_search import GlobalSearch
from symloc.scan import LaserScan
from symloc.symmetry.order import SymmetryOrder

from .types import Proposal, SymmetryVerdict, TrackerResult

__all__ = [
    "AmclTracker",
    "GlobalSearchProposer",
    "GridScorer",
    "ReportJudge",
    "corner_middle_bearing",
    "open_width",
    "verdict_from",
]

FloatArray = NDArray[np.float64]


class AmclTracker:
    """:class:`symloc.mcl.Amcl` as a :class:`~symloc.localizer.types.Tracker`.

    Each :meth:`update` runs the filter update (bounded cost), then its
    :class:`~symloc.mcl.confidence.ConfidenceJudge` on the result (the verdict, with the rival
    search when it is due), which fills ``TrackerResult.confident``.

    Parameters
    ----------
    amcl : Amcl
    laser_pose : (3,) array
        The laser in the robot frame (``base_from_laser``), given to every filter update.
    confidence : ConfidenceConfig, optional
        Thresholds of the verdict (default :class:`ConfidenceConfig()`).

    Attributes
    ----------
    judge : ConfidenceJudge
        Judges every filter result; starts afresh when the filter is re-initialised.
    last : AmclResult or None
        The filter's last result.
    last_confidence : Confidence or None
        The verdict on it.
    """

    def __init__(
        self,
        amcl: Amcl,
        *,
        laser_pose: ArrayLike = (0.0, 0.0, 0.0),
        confidence: ConfidenceConfig | None = None,
    ) -> None:
        self.amcl = amcl
        self.laser_pose = _pose3(laser_pose, "AmclTracker.laser_pose")
        self.judge = ConfidenceJudge(amcl, confidence)
        self.last: AmclResult | None = None
        self.last_confidence: Confidence | None = None

    def initialize_global(self) -> None:
        self.amcl.initialize_global()
        self.judge.reset()

    def initialize_pose(self, pose: FloatArray, covariance: FloatArray) -> None:
        self.amcl.initialize_pose(pose, covariance)
        self.judge.reset()

    def force_update(self) -> None:
        """Integrate the next scan whatever the robot moved (a claim was withdrawn)."""
        self.amcl.request_nomotion_update()

    def update(self, odom: Any, scan: Any) -> TrackerResult:
        r = self.amcl.update(odom, scan, laser_pose=self.laser_pose)
        conf = self.judge(r, odom, scan, laser_pose=self.laser_pose)
        self.last, self.last_confidence = r, conf
        hyps = tuple(r.hypotheses)  # the clusters are the localizer's hypotheses
        return TrackerResult(
            estimate=np.asarray(r.estimate, dtype=np.float64),
            covariance=np.asarray(r.covariance, dtype=np.float64),
            hypotheses=hyps,
            particles=np.asarray(r.particles),
            weights=np.asarray(r.weights),
            updated=bool(r.updated),
            confident=bool(conf.confident),
        )


def corner_middle_bearing(corners: NDArray[np.float64]) -> float | None:
    """Bearing [rad] in the sensor frame of the middle between two adjacent corners.

    ``corners`` (K, 2) in scan order; of the K middles the one nearest the robot's heading is
    returned (the smallest turn). ``None`` with fewer than 2 corners.
    """
    c = np.asarray(corners, dtype=np.float64).reshape(-1, 2)
    if c.shape[0] < 2:
        return None
    mids = 0.5 * (c + np.roll(c, -1, axis=0))
    bearings = np.arctan2(mids[:, 1], mids[:, 0])
    return float(bearings[int(np.argmin(np.abs(bearings)))])


def verdict_from(report: Any, laser_pose: ArrayLike | None = None) -> SymmetryVerdict:
    """Translate a :class:`symloc.symmetry.SymmetryReport` into a :class:`SymmetryVerdict`.

    The report's order passes through (None for an unknown verdict). A hallway is reported symmetric (order 2) but its
    centre along the axis is not observable, so it carries ``kind="hallway"``. The report is in
    the laser's frame; with ``laser_pose`` (3,) (``base_from_laser``) the centre, corners,
    facing bearing and axis of the verdict are in the robot's frame, where the robot drives.
    """
    order: SymmetryOrder | None = report.order
    center = np.asarray(report.center, dtype=np.float64).reshape(2)
    symmetric = bool(report.symmetric) and bool(np.all(np.isfinite(center)))
    corners = np.asarray(report.corners, dtype=np.float64).reshape(-1, 2)
    if laser_pose is not None:
        lp = _pose3(laser_pose, "laser_pose")
        c, s = math.cos(lp[2]), math.sin(lp[2])
        rot = np.array([[c, -s], [s, c]])
        center = rot @ center + lp[:2]
        corners = corners @ rot.T + lp[:2]
    facing = None
    finite = order is not None and not order.is_circle
    if (symmetric and finite and report.kind == "polygon") or (
        symmetric and report.kind == "rectangle" and corners.shape[0] == 4
    ):
        facing = corner_middle_bearing(corners)
    axis = None
    if symmetric and finite and report.kind == "polygon" and corners.shape[0] >= 2:
        mid = 0.5 * (corners[0] + corners[1]) - center
        axis = float(np.arctan2(mid[1], mid[0]))
    return SymmetryVerdict(
        symmetric=symmetric,
        order=order,
        kind=str(report.kind),
        center=center if symmetric else None,
        gv_distance=float(report.gv_distance),
        facing=facing,
        corners=corners,
        reason=str(report.reason),
        axis=axis,
    )


class ReportJudge:
    """Algorithm 1 as a :class:`~symloc.localizer.types.SymmetryJudge`.

    Parameters
    ----------
    judge : callable
        ``judge(scan, **kwargs) -> SymmetryReport`` (e.g. :func:`symloc.symmetry.judge_symmetry`).
    laser_pose : (3,) array, optional
        The laser in the robot frame: verdicts come out in the robot frame (:func:`verdict_from`).
    **kwargs
        Passed to ``judge`` on every call (e.g. ``config=SymmetryConfig(...)``).
    """

    def __init__(
        self, judge: Callable[..., Any], *, laser_pose: ArrayLike | None = None, **kwargs: Any
    ) -> None:
        self.judge = judge
        self.laser_pose = None if laser_pose is None else _pose3(laser_pose, "laser_pose")
        self.kwargs = kwargs
        self.last_report: Any = None
        #: judgements that raised (counted, treated as "unknown"); should stay 0.
        self.errors = 0
        self.last_error = ""

    def __call__(self, scan: Any) -> SymmetryVerdict:
        try:
            report = self.judge(scan, **self.kwargs)
        except (IndexError, ValueError, FloatingPointError, np.linalg.LinAlgError) as err:
            # a judgement bug must not stop the robot: count it, treat the scan as "unknown"
            self.errors += 1
            self.last_error = f"{type(err).__name__}: {err}"
            return SymmetryVerdict(
                False, None, "unknown", None, math.nan, reason=f"judge raised {self.last_error}"
            )
        self.last_report = report
        return verdict_from(report, self.laser_pose)


class GridScorer:
    """How well a scan fits an occupancy grid at given poses: mean of exp(-d^2 / 2 sigma^2).

    ``d`` is each beam end point's distance to the nearest occupied cell; points off the map or
    in unknown space count as far away. Score 1 is a perfect fit.

    Parameters
    ----------
    grid : OccupancyGrid or MapFields
        The map, or its shared fields (the distance to the nearest occupied cell is read from
        :meth:`~symloc.grid.fields.MapFields.obstacle_squared_cells`, 2 bytes per cell, when
        ``sigma`` is small enough that every distance beyond its reach scores exactly 0;
        else from :meth:`~symloc.grid.fields.MapFields.obstacle_distance`).
    sigma : float
        Standard deviation [m] of the fit (nav2's ``sigma_hit`` is 0.2).
    max_beams : int
        Beams used per scan (evenly sub-sampled).
    laser_pose : (3,) array
        The laser in the robot frame (``base_from_laser``); the scored poses are the robot's.
    """

    def __init__(
        self,
        grid: OccupancyGrid | MapFields,
        sigma: float = 0.05,
        max_beams: int = 120,
        *,
        laser_pose: ArrayLike = (0.0, 0.0, 0.0),
    ) -> None:
        self.laser_pose = _pose3(laser_pose, "GridScorer.laser_pose")
        fields = MapFields.of(grid)
        self.grid = fields.grid
        self.sigma = check_positive(sigma, "GridScorer.sigma")
        self.max_beams = int(max_beams)
        self._k: NDArray[np.uint16] | None = None
        self._metres: FloatArray | None = None
        self._dist: FloatArray | None = None
        reach = fields.obstacle_reach()
        if reach > _ZERO_SCORE_SIGMAS * self.sigma and self.grid.occupied_mask.any():
            self._k, self._metres = fields.obstacle_squared_cells()
        else:
            self._dist = fields.obstacle_distance()

    def __call__(self, poses: FloatArray, scan: LaserScan) -> FloatArray:
        """Scores (K,) in [0, 1] of ``scan`` at ``poses`` (K, 3)."""
        pts = scan.to_points()
        step = max(1, len(pts.ranges) // self.max_beams)
        r = np.asarray(pts.ranges)[::step]
        a = np.asarray(pts.angles)[::step]
        p = compose(np.asarray(poses, dtype=np.float64).reshape(-1, 3), self.laser_pose)
        ang = wrap_angle(p[:, 2:3] + a[None, :])
        xs = p[:, 0:1] + r[None, :] * np.cos(ang)
        ys = p[:, 1:2] + r[None, :] * np.sin(ang)
        cells = self.grid.world_to_cell(np.column_stack([xs.ravel(), ys.ravel()]))
        inside = self.grid.in_bounds(cells)
        d = np.full(cells.shape[0], 10.0 * self.sigma)
        if self._dist is not None:
            d[inside] = self._dist[cells[inside, 0], cells[inside, 1]]
        else:
            assert self._k is not None
            assert self._metres is not None
            d[inside] = self._metres[self._k[cells[inside, 0], cells[inside, 1]]]
        s = np.exp(-0.5 * (d / self.sigma) ** 2).reshape(p.shape[0], -1)
        return np.asarray(s.mean(axis=1) if s.shape[1] else np.zeros(p.shape[0]))


#: A distance of this many sigmas scores exp(-0.5 * 40^2) = exp(-800): 0.0 in float64 (below
#: the least subnormal, exp(-745.1)), so a clipped distance beyond it scores as the true one.
_ZERO_SCORE_SIGMAS = 40.0


def _pose3(value: ArrayLike, name: str) -> FloatArray:
    p = np.asarray(value, dtype=np.float64).reshape(-1)
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise ConfigurationError(f"{name}: expected finite (x [m], y [m], yaw [rad]), got {p}")
    return p


#: A map whose free space borders unmapped space (unknown cells or the grid's edge) along an
#: opening at least this wide [m] is open: the robot may stand where the map does not reach.
OPEN_WIDTH = 1.0


def open_width(grid: OccupancyGrid) -> float:
    """The widest opening [m] through which the map's free space meets unmapped space.

    Free cells with a 4-neighbour that is unknown are the map's frontier; the extent of its
    largest 8-connected piece is the opening (0 for a map closed by walls, or one with no
    unknown cells). A map that covers only part of the world (a mapping trip that left half a
    corridor out) has an opening about the width of the passage that goes on unmapped."""
    from scipy import ndimage

    free = np.asarray(grid.free_mask, dtype=bool)
    if not free.any():
        return 0.0
    unknown = np.asarray(grid.unknown_mask, dtype=bool)
    unmapped = np.pad(unknown, 1, constant_values=False)
    near = unmapped[:-2, 1:-1] | unmapped[2:, 1:-1] | unmapped[1:-1, :-2] | unmapped[1:-1, 2:]
    frontier = free & near
    if not frontier.any():
        return 0.0
    labels, _count = ndimage.label(frontier, structure=np.ones((3, 3), dtype=bool))
    widest = 0.0
    for sl in ndimage.find_objects(labels):
        if sl is None:
            continue
        rows = sl[0].stop - sl[0].start
        cols = sl[1].stop - sl[1].start
        widest = max(widest, math.hypot(rows, cols) * float(grid.resolution))
    return widest


class GlobalSearchProposer:
    """:class:`~symloc.mcl.global_search.GlobalSearch` as a
    :class:`~symloc.localizer.types.PoseProposer`: every distinct pose of the map that explains
    one scan (the laser at ``laser_pose`` on the robot, ``base_from_laser``).

    The search's list is complete for the map only: when the map is open (:func:`open_width`
    at least :data:`OPEN_WIDTH`), the robot may stand in the unmapped part of the world, and
    a place there may look like the one place of the map that explains the scan (half a
    corridor mapped: its one end is the 180-degree copy of the other). Every proposal is then
    incomplete, so that the laser alone never decides."""

    def __init__(self, search: GlobalSearch, *, laser_pose: ArrayLike = (0.0, 0.0, 0.0)) -> None:
        self.search = search
        self.laser_pose = _pose3(laser_pose, "GlobalSearchProposer.laser_pose")
        self._open: float | None = None

    @property
    def opening(self) -> float:
        """:func:`open_width` of the search's map [m] (measured once)."""
        if self._open is None:
            self._open = open_width(self.search.grid)
        return self._open

    def propose(self, scan: object) -> Proposal:
        if not isinstance(scan, LaserScan):
            raise ConfigurationError(
                f"GlobalSearchProposer.propose: expected a LaserScan, got {type(scan).__name__}"
            )
        found = self.search.search(scan, laser_pose=self.laser_pose)
        poses = np.array([c.pose for c in found.candidates], dtype=np.float64).reshape(-1, 3)
        scores = np.array([c.score for c in found.candidates], dtype=np.float64)
        complete = found.complete and not found.truncated
        reason = found.reason or (
            f"{found.n_distinct} poses explain the scan, only {len(found.candidates)} listed"
            if found.truncated
            else ""
        )
        if complete and self.opening >= OPEN_WIDTH:
            complete = False
            reason = (
                f"the map is open ({self.opening:.1f} m of free space meet unmapped space): "
                "poses outside the map may explain the scan as well"
            )
        return Proposal(poses, scores, complete, reason)
