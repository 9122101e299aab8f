"""The axis family: the laser knows the heading up to a half turn, not the position along a line.

In a long featureless corridor a scan fits equally well anywhere along the corridor, facing
either way: the poses that explain it share one heading up to a half turn (``theta`` and
``theta + pi``) and lie along lines parallel to the corridor's axis, one line per heading
class (the two lines coincide only when the robot stands on the centre line; off it, the
half-turned poses lie on the line mirrored about the centre line). This module

- recognises that family among the laser's hypotheses (:func:`axis_family`): one heading up
  to a half turn, the positions of each heading class on one line (a small perpendicular
  spread), spanning more than a short stretch along it;
- finds how far along its line each class explains the scan (:func:`sweep`: the scan scored
  at every step along the line, since the laser's list of poses is truncated in a corridor);
- tells whether the line runs on into space the map does not cover beyond an end
  (:func:`runs_out`: the map was built from a trip that did not reach the corridor's end, so
  the robot may stand where no pose of the map explains its scan);
- describes one heading class as a segment (:class:`AxisSegment`: its line, its heading and
  the stretch ``[lo, hi]`` along the line) with the covariance of a pose known to lie
  somewhere on it (:func:`axis_covariance`).

Which heading class is the right one, the laser cannot tell; the camera can
(:mod:`symloc.localizer.axis_heading`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc.errors import ConfigurationError
from symloc.geometry import compose, wrap_angle
from symloc.grid import OccupancyGrid

__all__ = [
    "AxisFamily",
    "AxisSegment",
    "axis_covariance",
    "axis_family",
    "line_reach",
    "map_corners",
    "open_stretch",
    "runs_out",
    "sweep",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: Scores of poses (K, 3) in [0, 1] (a scan against the map; higher fits better).
PoseScore = Callable[[FloatArray], FloatArray]


@dataclass(frozen=True, eq=False)
class AxisSegment:
    """One heading class of an axis family: the robot has heading ``heading`` [rad] and stands
    somewhere on the line through ``point`` (2,) [m] along ``unit`` (2,), between ``lo`` and
    ``hi`` [m] from ``point`` (``lo <= hi``)."""

    point: FloatArray
    unit: FloatArray
    heading: float
    lo: float
    hi: float

    @property
    def normal(self) -> FloatArray:
        """The unit normal (2,) of the line (``unit`` turned by +90 degrees)."""
        return np.array([-self.unit[1], self.unit[0]])

    @property
    def length(self) -> float:
        """The segment's length [m]."""
        return self.hi - self.lo

    @property
    def ends(self) -> FloatArray:
        """The segment's end points (2, 2) [m], ``lo`` first."""
        return self.point[None, :] + np.array([[self.lo], [self.hi]]) * self.unit[None, :]

    def at(self, s: ArrayLike) -> FloatArray:
        """Poses (K, 3) on the line at ``s`` (K,) [m] from ``point``, with the heading."""
        t = np.atleast_1d(np.asarray(s, dtype=np.float64))
        xy = self.point[None, :] + t[:, None] * self.unit[None, :]
        return np.column_stack([xy, np.full(t.shape[0], self.heading)])

    def middle(self) -> FloatArray:
        """The pose (3,) in the middle of the segment."""
        return np.asarray(self.at(0.5 * (self.lo + self.hi))[0], dtype=np.float64)

    def samples(self, spacing: float, most: int) -> FloatArray:
        """Poses (M, 3) evenly along the segment, ends included, at most ``spacing`` [m] apart
        unless that would take more than ``most`` poses (then evenly ``most``)."""
        count = max(1, min(most, math.ceil(self.length / spacing) + 1))
        if count == 1:
            return self.at(0.5 * (self.lo + self.hi))
        return self.at(np.linspace(self.lo, self.hi, count))

    def along(self, xy: FloatArray) -> FloatArray:
        """Coordinates (K,) [m] along the line of points ``xy`` (K, 2)."""
        return np.asarray((np.asarray(xy, dtype=np.float64) - self.point) @ self.unit)

    def across(self, xy: FloatArray) -> FloatArray:
        """Signed distances (K,) [m] of points ``xy`` (K, 2) from the line."""
        return np.asarray((np.asarray(xy, dtype=np.float64) - self.point) @ self.normal)


@dataclass(frozen=True, eq=False)
class AxisFamily:
    """Hypotheses that share one heading up to a half turn and lie along parallel lines.

    ``unit`` (2,) the axis direction; ``classes`` (K,) 0 for the hypotheses with ``headings[0]``
    (the first hypothesis' class) and 1 for the half-turned ones; ``headings`` (2,) [rad] each
    class' mean heading (``headings[1] = headings[0] + pi``); ``points`` (2, 2) [m] the mean
    position of each class (a point of its line; NaN for an empty class); ``spans`` (2, 2) [m]
    the least and greatest coordinate along ``unit`` of each class' positions from its point
    (NaN for an empty class); ``spread`` [m] the largest distance of a position from its
    class' line."""

    unit: FloatArray
    classes: IntArray
    headings: FloatArray
    points: FloatArray
    spans: FloatArray
    spread: float

    def count(self, c: int) -> int:
        """How many hypotheses class ``c`` holds."""
        return int(np.count_nonzero(self.classes == c))

    def segment(self, c: int) -> AxisSegment:
        """Class ``c`` (which must hold hypotheses) as the segment its positions span."""
        if self.count(c) == 0:
            raise ConfigurationError(f"AxisFamily.segment: class {c} holds no hypothesis")
        lo, hi = self.spans[c]
        return AxisSegment(self.points[c].copy(), self.unit.copy(), float(self.headings[c]), lo, hi)


def axis_family(
    poses: FloatArray,
    *,
    max_spread: float = 0.2,
    max_heading_spread: float = math.radians(10.0),
    min_length: float = 1.0,
    min_poses: int = 3,
) -> AxisFamily | None:
    """The axis family of ``poses`` (K, 3) [m, m, rad], best first, or None.

    Every pose must have the first one's heading up to a half turn (within
    ``max_heading_spread`` [rad] of its class' mean); the axis is the principal direction of
    the positions about their class' mean (both classes' scatter pooled, since the two lines
    are parallel but apart); every position must lie within ``max_spread`` [m] of its class'
    line, and one class must span at least ``min_length`` [m] along it, with ``min_poses``
    poses in all (two mirrored poses are a rectangle's copies, not an axis).
    """
    p = np.asarray(poses, dtype=np.float64).reshape(-1, 3)
    if p.shape[0] < max(min_poses, 2):
        return None
    turned = np.asarray(wrap_angle(p[:, 2] - p[0, 2]), dtype=np.float64)
    classes = (np.abs(turned) > 0.5 * math.pi).astype(np.int64)
    deviation = np.asarray(wrap_angle(turned - classes * math.pi), dtype=np.float64)
    mean = float(np.mean(deviation))
    if float(np.max(np.abs(deviation - mean))) > max_heading_spread:
        return None
    heading0 = float(wrap_angle(p[0, 2] + mean))
    headings = np.array([heading0, float(wrap_angle(heading0 + math.pi))])
    xy = p[:, :2]
    points = np.full((2, 2), np.nan)
    centred = np.empty_like(xy)
    for c in (0, 1):
        mask = classes == c
        if mask.any():
            points[c] = xy[mask].mean(axis=0)
            centred[mask] = xy[mask] - points[c]
    _w, v = np.linalg.eigh(centred.T @ centred)
    unit = np.asarray(v[:, -1], dtype=np.float64)
    if unit @ np.array([math.cos(heading0), math.sin(heading0)]) < 0.0:
        unit = -unit
    normal = np.array([-unit[1], unit[0]])
    spread = float(np.max(np.abs(centred @ normal)))
    along = centred @ unit
    spans = np.full((2, 2), np.nan)
    for c in (0, 1):
        mask = classes == c
        if mask.any():
            spans[c] = (float(along[mask].min()), float(along[mask].max()))
    length = float(np.nanmax(spans[:, 1] - spans[:, 0]))
    if spread > max_spread or length < min_length:
        return None
    return AxisFamily(unit, classes, headings, points, spans, spread)


def map_corners(grid: OccupancyGrid) -> FloatArray:
    """The four corners (4, 2) [m] of ``grid`` in the map frame."""
    w, h = grid.width * grid.resolution, grid.height * grid.resolution
    local = np.array([[0.0, 0.0, 0.0], [w, 0.0, 0.0], [0.0, h, 0.0], [w, h, 0.0]])
    return np.asarray(compose(grid.origin, local)[:, :2], dtype=np.float64)


def _cells(grid: OccupancyGrid, xy: FloatArray) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
    """Whether each point ``xy`` (..., 2) [m] lies in an occupied and in a known (occupied or
    free) cell of ``grid``; points off the grid are unknown."""
    flat = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    cells = grid.world_to_cell(flat)
    inside = grid.in_bounds(cells)
    occupied = np.zeros(flat.shape[0], dtype=bool)
    known = np.zeros(flat.shape[0], dtype=bool)
    rc = cells[inside]
    occupied[inside] = grid.occupied_mask[rc[:, 0], rc[:, 1]]
    known[inside] = occupied[inside] | grid.free_mask[rc[:, 0], rc[:, 1]]
    shape = np.asarray(xy).shape[:-1]
    return occupied.reshape(shape), known.reshape(shape)


def open_stretch(segment: AxisSegment, grid: OccupancyGrid, s: float) -> float:
    """The length [m] of the stretch of ``segment``'s line through ``s`` [m] that no occupied
    cell of ``grid`` crosses: a corridor's length from end wall to end wall (the grid's edge
    where no wall closes it)."""
    step = float(grid.resolution)
    lo, hi = line_reach(segment, map_corners(grid))
    ts = np.arange(lo, hi + 0.5 * step, step)
    occupied, _ = _cells(grid, segment.at(ts)[:, :2])
    k = int(np.clip(np.searchsorted(ts, s), 0, ts.size - 1))
    before = np.flatnonzero(occupied[:k])
    after = np.flatnonzero(occupied[k:])
    start = ts[before[-1]] if before.size else ts[0]
    end = ts[k + after[0]] if after.size else ts[-1]
    return float(end - start)


def _free_reach(segment: AxisSegment, grid: OccupancyGrid, s: float, side: float) -> float:
    """How far [m] the free space reaches from the line at ``s`` towards ``side`` (+1: along
    the normal, -1: against it), up to 5 m: the corridor's half-width on that side."""
    step = float(grid.resolution)
    d = step * np.arange(1, int(5.0 / step) + 1)
    xy = segment.at(s)[0, :2][None, :] + side * d[:, None] * segment.normal[None, :]
    occupied, known = _cells(grid, xy)
    stop = np.flatnonzero(occupied | ~known)
    return float(d[stop[0]]) if stop.size else float(d[-1])


def runs_out(
    segment: AxisSegment,
    grid: OccupancyGrid,
    s: float,
    direction: int,
    *,
    unmapped: float = 0.5,
    solid: float = 0.8,
) -> bool:
    """Does the line run on into unmapped space beyond ``s`` [m] (walking towards
    ``direction``: +1 or -1 along ``unit``)?

    Walked cell by cell until it leaves ``grid``. An end wall closes it: occupied cells (within
    a cell along the line, a wall crossed at a slant) across at least ``solid`` of the
    corridor's width, as the free space reaches either side of the line at ``s``; an obstacle
    in the corridor, or scattered occupied cells of a badly mapped stretch, do not. True when
    ``unmapped`` [m] in a row of unknown cells (or the grid's edge) on the line come before
    such a wall, or no wall comes at all; False when a wall closes it first. A few unknown
    cells in the free space (a SLAM map's holes) do not open it."""
    step = float(grid.resolution)
    reach = line_reach(segment, map_corners(grid))
    far = reach[1] - s if direction > 0 else s - reach[0]
    n = max(1, math.ceil(max(far, 0.0) / step) + 1)
    ts = s + direction * step * np.arange(1, n + 1)
    left, right = _free_reach(segment, grid, s, 1.0), _free_reach(segment, grid, s, -1.0)
    offsets = np.arange(-right, left + 0.5 * step, step)
    xy = segment.at(ts)[:, None, :2] + offsets[None, :, None] * segment.normal[None, None, :]
    occupied, known = _cells(grid, xy)
    near = occupied.copy()
    near[1:] |= occupied[:-1]
    near[:-1] |= occupied[1:]
    walls = np.flatnonzero(near.mean(axis=1) >= solid)
    wall = int(walls[0]) if walls.size else n
    unknown = (~known[:, int(np.argmin(np.abs(offsets)))]).astype(np.int64)
    # length of the run of unknown cells ending at each cell
    total = np.cumsum(unknown)
    runs = total - np.maximum.accumulate(np.where(unknown == 0, total, 0))
    opened = np.flatnonzero(runs >= max(1, round(unmapped / step)))
    first_open = int(opened[0]) if opened.size else n
    return first_open < wall or wall == n


def line_reach(segment: AxisSegment, corners: FloatArray) -> tuple[float, float]:
    """The least and greatest coordinate [m] along ``segment``'s line of the points
    ``corners`` (K, 2) (e.g. the map's corners): how far the line can reach on the map."""
    s = segment.along(np.asarray(corners, dtype=np.float64).reshape(-1, 2))
    return float(s.min()), float(s.max())


def sweep(
    score: PoseScore,
    segment: AxisSegment,
    lo: float,
    hi: float,
    *,
    step: float = 0.1,
    across: float = 0.1,
    across_step: float = 0.05,
    ratio: float = 0.9,
) -> tuple[AxisSegment, float] | None:
    """The stretch of ``segment``'s line between ``lo`` and ``hi`` [m] where the scan fits,
    and the share of that stretch where it does.

    The line is sampled every ``step`` [m]; each sample takes the best ``score`` over offsets
    up to ``across`` [m] either side of the line (every ``across_step``), which absorbs a line
    slightly off its true direction. Samples scoring at least ``ratio`` of the best sample
    explain the scan; the stretch spans the first to the last of them (gaps included: the
    robot may stand in any of them), with the segment's heading, and the share is how many of
    its samples explain the scan (1 along a featureless corridor; repeated features, such as
    pillars, leave gaps). None when no sample scores above 0."""
    s = np.arange(lo, hi + 0.5 * step, step)
    if s.size == 0:
        s = np.array([0.5 * (lo + hi)])
    offsets = np.arange(-across, across + 0.5 * across_step, across_step)
    base = segment.at(s)
    shift = offsets[None, :, None] * segment.normal[None, None, :]
    xy = base[:, None, :2] + shift
    poses = np.concatenate([xy, np.full((*xy.shape[:2], 1), segment.heading)], axis=2)
    scores = np.asarray(score(poses.reshape(-1, 3)), dtype=np.float64)
    best_across = scores.reshape(s.size, offsets.size)
    per_sample = best_across.max(axis=1)
    best = float(per_sample.max())
    if not best > 0.0:
        return None
    fits = per_sample >= ratio * best
    inside = np.flatnonzero(fits)
    share = float(np.mean(fits[inside[0] : inside[-1] + 1]))
    # the line moved onto the best offset of the best sample (the laser's side position)
    k = int(np.argmax(per_sample))
    point = segment.point + offsets[int(np.argmax(best_across[k]))] * segment.normal
    lo_fit, hi_fit = float(s[inside[0]]), float(s[inside[-1]])
    return AxisSegment(point, segment.unit.copy(), segment.heading, lo_fit, hi_fit), share


def axis_covariance(
    segment: AxisSegment, across_std: float, heading_std: float, pad: float = 0.0
) -> FloatArray:
    """The covariance (3, 3) [m^2, rad^2] of a pose known to lie somewhere on ``segment``
    (uniformly, lengthened by ``pad`` [m] at each end: std ``(length + 2 pad) / sqrt(12)``
    along the line), ``across_std`` [m] across it and ``heading_std`` [rad] in heading.

    The 95 % ellipsoid of three degrees of freedom (squared Mahalanobis distance 7.81) reaches
    0.81 of the length either side of the middle along the line: every point of the segment
    lies inside it."""
    along_var = (segment.length + 2.0 * pad) ** 2 / 12.0
    frame = np.column_stack([segment.unit, segment.normal])
    cov = np.zeros((3, 3))
    cov[:2, :2] = frame @ np.diag([along_var, across_std**2]) @ frame.T
    cov[2, 2] = heading_std**2
    return cov
