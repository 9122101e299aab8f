"""Log-odds occupancy mapping with an inverse sensor model (Thrun et al. 2005, Table 9.1-9.2).

Each scan at a known pose updates every cell its beams touch once: cells a beam passes
through become more likely free (``log_odds(p_miss)``), the cell of a beam's end point more
likely occupied (``log_odds(p_hit)``), and the values are clamped to
``[log_odds(p_min), log_odds(p_max)]`` so the map stays able to change (Cartographer's
probability grid does the same). Cell traversal samples points along every beam at half a cell
(vectorised over all beams of a scan); the end-point cell is never also marked free.

- A valid reading beyond ``max_range`` is truncated: free up to ``max_range``, no hit.
- A no-return reading (``>= range_max`` of the scan) clears free space only up to
  ``no_return_range`` (0 disables it) and never adds a hit.
- Invalid readings (NaN, below ``range_min``) do nothing.

:class:`LogOddsGrid` grows as scans reach beyond it and converts to an
:class:`~symloc.grid.OccupancyGrid`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc._checks import check_positive
from symloc.errors import ConfigurationError
from symloc.grid.occupancy_grid import OccupancyGrid
from symloc.scan import LaserScan

__all__ = ["InverseSensorModel", "LogOddsGrid", "beam_cells", "log_odds", "probability"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]

#: Beams whose free-space samples are computed at once (bounds the temporaries: a 40 m beam
#: at 5 cm cells is 1600 samples).
_BEAM_CHUNK = 64


def log_odds(p: ArrayLike) -> FloatArray:
    """``log(p / (1 - p))`` for probabilities in (0, 1)."""
    q = np.asarray(p, dtype=np.float64)
    return np.log(q / (1.0 - q))


def probability(lo: ArrayLike) -> FloatArray:
    """Inverse of :func:`log_odds`: ``1 / (1 + exp(-lo))``."""
    return 1.0 / (1.0 + np.exp(-np.asarray(lo, dtype=np.float64)))


@dataclass(frozen=True, slots=True)
class InverseSensorModel:
    """Settings of the inverse sensor model.

    Parameters
    ----------
    p_hit, p_miss : float
        Occupancy probability assigned to an end-point cell (> 0.5) and to a traversed cell
        (< 0.5).
    p_min, p_max : float
        Clamping bounds of a cell's probability, ``0 < p_min < p_miss < p_hit < p_max < 1``.
    max_range : float
        Readings farther than this [m] are truncated (free up to it, no hit).
    no_return_range : float
        Free space cleared along a no-return beam [m]; 0 disables.
    step : float
        Sampling step along a beam in cells (<= 1; 0.5 visits every cell a beam crosses
        except a few corner-clipped ones).
    """

    p_hit: float = 0.7
    p_miss: float = 0.4
    p_min: float = 0.12
    p_max: float = 0.97
    max_range: float = 30.0
    no_return_range: float = 5.0
    step: float = 0.5

    def __post_init__(self) -> None:
        if not 0.0 < self.p_min < self.p_miss < 0.5 < self.p_hit < self.p_max < 1.0:
            raise ConfigurationError(
                "InverseSensorModel: expected 0 < p_min < p_miss < 0.5 < p_hit < p_max < 1, got"
                f" p_min={self.p_min}, p_miss={self.p_miss}, p_hit={self.p_hit},"
                f" p_max={self.p_max}"
            )
        check_positive(self.max_range, "InverseSensorModel.max_range")
        check_positive(self.no_return_range, "InverseSensorModel.no_return_range", allow_zero=True)
        step = check_positive(self.step, "InverseSensorModel.step")
        if step > 1.0:
            raise ConfigurationError(f"InverseSensorModel.step: expected <= 1 cell, got {step}")

    @property
    def l_hit(self) -> float:
        """Log-odds increment of a hit cell."""
        return float(log_odds(self.p_hit))

    @property
    def l_miss(self) -> float:
        """Log-odds increment (negative) of a traversed cell."""
        return float(log_odds(self.p_miss))

    @property
    def l_min(self) -> float:
        """Lower clamp of a cell's log-odds."""
        return float(log_odds(self.p_min))

    @property
    def l_max(self) -> float:
        """Upper clamp of a cell's log-odds."""
        return float(log_odds(self.p_max))


def _beam_geometry(
    scan: LaserScan, model: InverseSensorModel
) -> tuple[FloatArray, FloatArray, NDArray[np.bool_]]:
    """Per-beam angle (B,), free length (B,) [m] and hit flag (B,) of the usable beams."""
    r = scan.ranges
    angles = scan.angles
    valid = scan.valid_mask
    no_ret = scan.no_return_mask
    hit = valid & (r <= model.max_range)
    length = np.where(valid, np.minimum(r, model.max_range), 0.0)
    if model.no_return_range > 0:
        length = np.where(no_ret, model.no_return_range, length)
    use = length > 0
    return angles[use], np.where(np.isfinite(length[use]), length[use], 0.0), hit[use]


def _raw_cells(
    pose: ArrayLike,
    scan: LaserScan,
    model: InverseSensorModel,
    resolution: float,
    origin_xy: ArrayLike,
) -> tuple[IntArray, IntArray, IntArray, IntArray]:
    """Rows and columns of every beam sample (free, with repeats) and of every hit."""
    p = np.asarray(pose, dtype=np.float64)
    o = np.asarray(origin_xy, dtype=np.float64)
    ang, length, hit = _beam_geometry(scan, model)
    world_ang = p[2] + ang
    c, s = np.cos(world_ang), np.sin(world_ang)
    step = model.step * resolution
    n = np.ceil(length / step).astype(np.intp)
    total = int(n.sum())
    beam = np.repeat(np.arange(ang.size), n)
    start = np.cumsum(n) - n
    t = (np.arange(total) - start[beam]) * step
    fx = np.floor((p[0] - o[0] + t * c[beam]) / resolution).astype(np.intp)
    fy = np.floor((p[1] - o[1] + t * s[beam]) / resolution).astype(np.intp)
    hx = np.floor((p[0] - o[0] + length[hit] * c[hit]) / resolution).astype(np.intp)
    hy = np.floor((p[1] - o[1] + length[hit] * s[hit]) / resolution).astype(np.intp)
    return fy, fx, hy, hx


def beam_cells(
    pose: ArrayLike,
    scan: LaserScan,
    model: InverseSensorModel,
    resolution: float,
    origin_xy: ArrayLike,
) -> tuple[IntArray, IntArray]:
    """Cells a scan at ``pose`` marks free and occupied.

    Parameters
    ----------
    pose : array of shape (3,)
        Sensor pose in the grid's world frame.
    scan : LaserScan
    model : InverseSensorModel
    resolution : float
        Cell edge [m].
    origin_xy : array of shape (2,)
        World position of the corner of cell (0, 0) (axis-aligned grid).

    Returns
    -------
    free : ndarray of shape (F, 2)
        Unique (row, col) cells traversed by a beam and not holding any beam's end point.
    hits : ndarray of shape (K, 2)
        Unique (row, col) cells holding an end point.
    """
    fy, fx, hy, hx = _raw_cells(pose, scan, model, resolution, origin_xy)
    big = np.int64(1 << 31)
    off = np.int64(1 << 30)
    key_f = np.unique((fy.astype(np.int64) + off) * big + (fx + off))
    key_h = np.unique((hy.astype(np.int64) + off) * big + (hx + off))
    key_f = key_f[~np.isin(key_f, key_h, assume_unique=True)]

    def _split(k: NDArray[np.int64]) -> IntArray:
        return np.column_stack([k // big - off, k % big - off]).astype(np.intp).reshape(-1, 2)

    return _split(key_f), _split(key_h)


class LogOddsGrid:
    """An axis-aligned log-odds grid that grows to hold every scan integrated into it.

    Parameters
    ----------
    resolution : float
        Cell edge [m].
    model : InverseSensorModel, optional
    origin_xy : array of shape (2,), optional
        Initial world position of the corner of cell (0, 0); the grid starts empty (1 x 1).
    chunk : int
        Cells added per side when the grid grows.
    clamp : bool
        Clamp every cell to ``[model.l_min, model.l_max]`` after each scan (default), so that
        the grid can change: its cells follow the latest observations. False sums all the
        evidence, whatever its order: a cell is then occupied when enough of the beams that
        reached it ended in it (with the defaults, about a third), which is what a map of a
        static world built from a whole run should say. Clamped, a wall cell seen head-on
        hundreds of times is cleared by a few beams that graze it on their way to a farther
        point of the same wall (a robot driving along a wall), and the wall's inner face
        erodes to the cells behind it.
    """

    def __init__(
        self,
        resolution: float,
        model: InverseSensorModel | None = None,
        origin_xy: ArrayLike = (0.0, 0.0),
        *,
        chunk: int = 64,
        clamp: bool = True,
    ) -> None:
        self.resolution = check_positive(resolution, "resolution")
        self.model = model if model is not None else InverseSensorModel()
        self.origin_xy = np.asarray(origin_xy, dtype=np.float64).reshape(2).copy()
        self.values = np.zeros((1, 1), dtype=np.float32)
        # reserved memory (see reserve): values is the window of _buffer starting at _view
        self._buffer: NDArray[np.float32] | None = None
        self._view = (0, 0)
        self.chunk = int(chunk)
        self.clamp = bool(clamp)
        self.n_scans = 0

    @property
    def shape(self) -> tuple[int, int]:
        """``(H, W)`` cells."""
        return (int(self.values.shape[0]), int(self.values.shape[1]))

    def ensure_contains(self, xy_min: ArrayLike, xy_max: ArrayLike) -> None:
        """Grow the grid so that the world box ``[xy_min, xy_max]`` lies inside it."""
        pads = _growth(self.origin_xy, self.shape, xy_min, xy_max, self.resolution, self.chunk)
        if not any(pads):
            return
        pl, pb, pr, pt = pads
        h, w = self.values.shape
        buf = self._buffer
        if buf is not None and (
            self._view[0] >= pb
            and self._view[1] >= pl
            and self._view[0] + h + pt <= buf.shape[0]
            and self._view[1] + w + pr <= buf.shape[1]
        ):
            # reserved: the grown grid is a larger window of the same zero-initialised buffer
            r0, c0 = self._view[0] - pb, self._view[1] - pl
            self._view = (r0, c0)
            self.values = buf[r0 : r0 + h + pb + pt, c0 : c0 + w + pl + pr]
        else:
            self.values = np.pad(self.values, ((pb, pt), (pl, pr)))
            self._buffer = None
        self.origin_xy = self.origin_xy - np.array([pl, pb]) * self.resolution

    def reserve(self, poses: ArrayLike, scans: Sequence[LaserScan]) -> None:
        """Allocate at once the grid that integrating ``scans`` at ``poses`` (N, 3) will grow
        to, so that growing exposes zero cells of it instead of copying the grid each time.

        The grid's shape and origin after every scan are exactly those without reserving (the
        same growth steps are computed in advance); only the memory is allocated once, which
        keeps a large map from holding its old and new copies at every growth step.
        """
        p = np.asarray(poses, dtype=np.float64).reshape(-1, 3)
        if len(scans) != p.shape[0]:
            raise ConfigurationError(
                f"poses: expected one per scan ({len(scans)}), got {p.shape[0]}"
            )
        origin = self.origin_xy.copy()
        h, w = self.shape
        top = left = 0  # cells added below row 0 / left of column 0 of the current grid
        for pose, scan in zip(p, scans, strict=True):
            reach = self._reach(scan)
            pl, pb, pr, pt = _growth(
                origin, (h, w), pose[:2] - reach, pose[:2] + reach, self.resolution, self.chunk
            )
            if pl or pb or pr or pt:
                origin = origin - np.array([pl, pb]) * self.resolution
                h, w = h + pb + pt, w + pl + pr
                top, left = top + pb, left + pl
        if (h, w) == self.shape:
            return
        buf = np.zeros((h, w), dtype=np.float32)
        h0, w0 = self.shape
        buf[top : top + h0, left : left + w0] = self.values
        self._buffer = buf
        self._view = (top, left)
        self.values = buf[top : top + h0, left : left + w0]

    def _reach(self, scan: LaserScan) -> float:
        """Half-width [m] of the square around the sensor that ``scan`` can change."""
        reach = 0.0
        r = scan.ranges[scan.valid_mask]
        if r.size:
            reach = min(self.model.max_range, float(r.max()))
        if self.model.no_return_range > 0 and np.any(scan.no_return_mask):
            reach = max(reach, self.model.no_return_range)
        return reach + 2 * self.resolution

    def integrate(self, pose: ArrayLike, scan: LaserScan) -> None:
        """Update the grid with ``scan`` taken at sensor pose ``pose`` (3,) [m, m, rad]."""
        p = np.asarray(pose, dtype=np.float64)
        reach = self._reach(scan)
        self.ensure_contains(p[:2] - reach, p[:2] + reach)
        res = self.resolution
        o = self.origin_xy
        ang, length, hit = _beam_geometry(scan, self.model)
        if ang.size == 0:
            self.n_scans += 1
            return
        # one update per cell: mark a window covering the scan, hits override free
        h, w = self.values.shape
        r0 = max(int(np.floor((p[1] - reach - o[1]) / res)), 0)
        c0 = max(int(np.floor((p[0] - reach - o[0]) / res)), 0)
        r1 = min(int(np.floor((p[1] + reach - o[1]) / res)) + 1, h)
        c1 = min(int(np.floor((p[0] + reach - o[0]) / res)) + 1, w)
        mark = np.zeros((r1 - r0, c1 - c0), dtype=np.int8)
        world_ang = p[2] + ang
        c, s = np.cos(world_ang), np.sin(world_ang)
        step = self.model.step * res
        for b0 in range(0, ang.size, _BEAM_CHUNK):  # bounded temporaries for long beams
            sl = slice(b0, b0 + _BEAM_CHUNK)
            n = np.ceil(length[sl] / step).astype(np.intp)
            beam = np.repeat(np.arange(n.size), n)
            t = (np.arange(int(n.sum())) - (np.cumsum(n) - n)[beam]) * step
            fx = np.floor((p[0] - o[0] + t * c[sl][beam]) / res).astype(np.intp) - c0
            fy = np.floor((p[1] - o[1] + t * s[sl][beam]) / res).astype(np.intp) - r0
            mark[fy, fx] = 1
        hx = np.floor((p[0] - o[0] + length[hit] * c[hit]) / res).astype(np.intp) - c0
        hy = np.floor((p[1] - o[1] + length[hit] * s[hit]) / res).astype(np.intp) - r0
        mark[hy, hx] = 2
        win = self.values[r0:r1, c0:c1]
        win[mark == 1] += np.float32(self.model.l_miss)
        win[mark == 2] += np.float32(self.model.l_hit)
        if self.clamp:
            np.clip(win, self.model.l_min, self.model.l_max, out=win)
        self.n_scans += 1

    def probability(self) -> FloatArray:
        """``(H, W)`` occupancy probability; never-observed cells are 0.5."""
        return probability(self.values)

    def occupancy_percent(self) -> NDArray[np.int8]:
        """``(H, W)`` occupancy 0..100 (rounded), computed in float32 (half the memory)."""
        return _occupancy_percent(self.values)

    def known_mask(self) -> NDArray[np.bool_]:
        """``(H, W)`` True where the cell was observed (log-odds not 0)."""
        return np.asarray(self.values != 0, dtype=bool)

    def to_occupancy_grid(
        self,
        *,
        occupied_thresh: float = 0.65,
        free_thresh: float = 0.196,
        crop_margin: int | None = None,
    ) -> OccupancyGrid:
        """The grid as an :class:`OccupancyGrid`: unknown -1 where never observed, else 0..100.

        With ``crop_margin`` (cells), the result is cropped to the observed cells' bounding
        box plus that margin (the crop is chosen first and only its cells are converted).
        """
        v = self.values
        origin = self.origin_xy.copy()
        if crop_margin is not None:
            rows = np.flatnonzero(v.any(axis=1))
            if rows.size:
                cols = np.flatnonzero(v.any(axis=0))
                m = int(crop_margin)
                r0, r1 = max(rows[0] - m, 0), min(rows[-1] + m + 1, v.shape[0])
                c0, c1 = max(cols[0] - m, 0), min(cols[-1] + m + 1, v.shape[1])
                v = v[r0:r1, c0:c1]
                origin = origin + np.array([c0, r0]) * self.resolution
        occ = _occupancy_percent(v, unknown=-1)
        return OccupancyGrid(
            occ,
            self.resolution,
            np.array([origin[0], origin[1], 0.0]),
            occupied_thresh,
            free_thresh,
        )


#: Cells converted at once by :func:`_occupancy_percent` (bounds its float32 temporaries).
_BLOCK_CELLS = 1 << 20


def _occupancy_percent(values: NDArray[np.float32], unknown: int | None = None) -> NDArray[np.int8]:
    """``(H, W)`` occupancy 0..100 of log-odds ``values (H, W)``, rounded, computed in float32
    a block of rows at a time; cells at exactly 0 (never observed) get ``unknown`` if given."""
    h, w = values.shape
    out = np.empty((h, w), dtype=np.int8)
    step = max(1, _BLOCK_CELLS // max(w, 1))
    for a in range(0, h, step):
        blk = values[a : a + step]
        v = blk.astype(np.float32, copy=True)
        np.clip(v, -30.0, 30.0, out=v)  # an unclamped grid's sums: no overflow in exp
        np.negative(v, out=v)
        np.exp(v, out=v)
        v += np.float32(1.0)
        np.divide(np.float32(100.0), v, out=v)
        np.rint(v, out=v)
        o = out[a : a + step]
        o[...] = v.astype(np.int8)
        if unknown is not None:
            o[blk == 0] = unknown
    return out


def _growth(
    origin_xy: FloatArray,
    shape: tuple[int, int],
    xy_min: ArrayLike,
    xy_max: ArrayLike,
    resolution: float,
    chunk: int,
) -> tuple[int, int, int, int]:
    """Cells ``(left, bottom, right, top)`` a grid of ``shape (H, W)`` with its cell (0, 0) at
    ``origin_xy (2,)`` [m] grows by to hold the world box ``[xy_min, xy_max]`` (``chunk`` more
    on every side that grows; all 0 when the box is inside)."""
    lo = np.floor((np.asarray(xy_min, float) - origin_xy) / resolution).astype(int)
    hi = np.floor((np.asarray(xy_max, float) - origin_xy) / resolution).astype(int)
    h, w = shape
    pad_left = max(0, -lo[0])
    pad_bottom = max(0, -lo[1])
    pad_right = max(0, hi[0] - (w - 1))
    pad_top = max(0, hi[1] - (h - 1))
    return (
        int(pad_left + chunk if pad_left else 0),
        int(pad_bottom + chunk if pad_bottom else 0),
        int(pad_right + chunk if pad_right else 0),
        int(pad_top + chunk if pad_top else 0),
    )
