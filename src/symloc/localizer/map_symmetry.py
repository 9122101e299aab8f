"""Rotational self-symmetry of an occupancy grid (is the *map* itself symmetric?).

A pose that AMCL converged to cannot be earned when the map maps onto itself under a rotation
that also carries the pose onto a copy explaining the scan as well: in a 40 m hallway whose far
ends the lidar sees one at a time, the two ends look alike and AMCL's particles die out at one
of them by chance. :func:`map_symmetries` finds such rotations once per map: the occupied cells
are rotated by ``2 pi / k`` about a centre and the share of rotated cells landing within
``tolerance`` of an occupied cell (the *overlap*) is measured; orders whose overlap reaches
``min_overlap`` are symmetries of the map. The default (0.6) keeps *near* symmetries too (a
rectangle with one box, uneven chamfers): whether the scan tells their copies apart is the
localizer's decision, made with the scan.

The centre is searched over the whole map, not near one guess: rotating about ``c`` is
rotating about the origin and then shifting by ``(I - R) c``, so the overlap of every centre
whose shift is a whole number of cells is one cross-correlation of the rotated cells with the
cells near an obstacle (an FFT per order). A feature that breaks the symmetry (a box, a door,
a wing of the room) cannot pull the search off the rotation centre, and a symmetric *part* of
the map (the bar of a T-shaped room, one wing of an L) is found about its own centre. Each
order keeps up to :data:`MAX_CENTRES` centres, every one a local maximum of the overlap within
:data:`SEPARATION` of itself, refined off the cell lattice by a short local search.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from numpy.typing import NDArray
from scipy.fft import irfft2, next_fast_len, rfft2
from scipy.ndimage import maximum_filter
from scipy.signal import fftconvolve

from symloc._checks import check_in_range, check_positive
from symloc.grid import OccupancyGrid
from symloc.grid.fields import MapFields

__all__ = [
    "MAX_CENTRES",
    "PARTIAL_OVERLAP",
    "ROUND_TURNS",
    "SEPARATION",
    "MapSymmetry",
    "map_symmetries",
    "round_centre",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]
BoolArray = NDArray[np.bool_]

logger = logging.getLogger(__name__)

#: The least overlap of a partial near symmetry the localizer asks for
#: (:func:`symloc.localizer.build.grid_symmetries`): the bar of a T-shaped room is 30-60 %
#: of its walls, less on a SLAM map (44 % on a dev world whose bar is 11 m of a T 15 m long).
PARTIAL_OVERLAP = 0.4
#: Most centres kept per order (distinct local maxima of the overlap, best first).
MAX_CENTRES = 3
#: Two centres of one order closer than this [m] are one; a centre must be the best within it.
SEPARATION = 1.0
#: A centre whose overlap never drops below this share of its own on the way to a better
#: centre of the same order lies on the better one's ridge (a corridor's axis) and is dropped.
RIDGE = 0.8
#: Largest correlation (cells) computed at the map's resolution; a larger map (a 60 m
#: corridor) is correlated on cells 2, 4, ... times coarser, which bounds the overlap from
#: above, and is counted exactly only around the bound's local maxima. Every order is first
#: bounded on cells twice as coarse and skipped when no centre can reach the threshold. Cost
#: (CPU, one core): 12-150 ms on the dev SLAM maps (median 38 ms), 60 ms for the 40 m
#: hallway with its lab, 0.5 s for a 60 m x 60 m grid of offices (25,000 occupied cells).
MAX_FFT_CELLS = 1 << 18
#: Bytes of shifted windows :func:`_window_counts` gathers at once (bounds its memory).
WINDOW_BYTES = 1 << 24
#: Above this many cell-window reads (cells x size^2) :func:`_window_counts` correlates by FFT.
DIRECT_WINDOW_WORK = 1 << 30
#: Side [cells] of the tiles the FFT correlation of :func:`_window_counts_fft` works on.
FFT_TILE = 1024
#: Occupied cells turned at a time by :func:`_overlap` (its float64 temporaries: 16 MiB each).
OVERLAP_CHUNK = 1 << 20
#: Local maxima of one order's overlap looked at (when the map is correlated coarsely: counted
#: exactly around each).
PEAKS = 12


@dataclass(frozen=True)
class MapSymmetry:
    """The map maps onto itself when rotated by ``2 pi / order`` about ``centre`` (2,) [m];
    ``overlap`` is the share of occupied cells that land on occupied cells. ``partial``: the
    overlap is below the whole-map threshold, only a part of the map (the bar of a T-shaped
    room) is symmetric about ``centre`` (see ``min_partial`` of :func:`map_symmetries`)."""

    centre: FloatArray
    order: int
    overlap: float
    partial: bool = False


@dataclass(frozen=True, eq=False)
class _Cells:
    """What the search reads from the map, cropped to the occupied cells' bounding box (plus
    the tolerance): ``xy`` (N, 2) the occupied cells as integer (column, row) coordinates in
    the crop, ``offset`` (2,) the crop's first (column, row) in the grid, ``world`` (N, 2) the
    cells' centres [m] and ``hits`` (H, W) the crop's cells within the tolerance of an occupied
    cell."""

    xy: IntArray
    offset: IntArray
    world: FloatArray
    hits: BoolArray

    @classmethod
    def of(cls, grid: OccupancyGrid, near: BoolArray, margin: int) -> _Cells:
        """The occupied cells of ``grid`` and the cells ``near`` (H, W) one, cropped with a
        border of ``margin`` cells."""
        rc = np.argwhere(np.asarray(grid.occupied_mask, dtype=bool))
        lo = np.maximum(rc.min(axis=0) - margin, 0)
        hi = np.minimum(rc.max(axis=0) + margin + 1, near.shape)
        return cls(
            xy=(rc - lo)[:, ::-1].astype(np.intp),
            offset=lo[::-1].astype(np.intp),
            world=np.asarray(grid.cell_to_world(rc), dtype=np.float64),
            hits=near[lo[0] : hi[0], lo[1] : hi[1]],
        )


def map_symmetries(
    grid: OccupancyGrid | MapFields,
    orders: tuple[int, ...] = (2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12),
    *,
    tolerance: float = 0.1,
    min_overlap: float = 0.6,
    min_partial: float | None = None,
) -> list[MapSymmetry]:
    """The rotational symmetries of ``grid``, each about the centre that suits it best.

    Parameters
    ----------
    grid : OccupancyGrid or MapFields
        The map, or its shared fields (the cells near an occupied cell are read from
        :meth:`~symloc.grid.fields.MapFields.near_obstacle`).
    orders : tuple of int
        Orders k (>= 2) to test (rotation by ``2 pi / k``).
    tolerance : float
        A rotated occupied cell matches when it lies within this distance [m] of an occupied cell.
    min_overlap : float
        Share in (0, 1] of occupied cells that must match.
    min_partial : float, optional
        Also report *partial* near symmetries: centres about which at least this share (in
        (0, ``min_overlap``]) of the occupied cells match, a symmetric part of the map (the
        bar of a T-shaped room, one wing of an L) rather than the whole
        (``MapSymmetry.partial``), whose centre lies in the map's free space (a part the robot
        can be in). None: whole-map symmetries only. The localizer asks for
        them (:data:`PARTIAL_OVERLAP`): their copies are checked against the scan like any
        other, so a looser list costs time and refusals, never a wrong claim.

    Returns
    -------
    list of MapSymmetry
        Every tested order that passes, highest order first, up to :data:`MAX_CENTRES` centres
        per order (best overlap first); empty for an asymmetric map.
    """
    check_positive(tolerance, "tolerance")
    check_in_range(min_overlap, "min_overlap", 1e-9, 1.0)
    least = min_overlap
    if min_partial is not None:
        least = check_in_range(min_partial, "min_partial", 1e-9, min_overlap)
    fields = MapFields.of(grid)
    grid = fields.grid
    if int(np.count_nonzero(grid.occupied_mask)) < 10:
        return []
    margin = math.ceil(tolerance / grid.resolution) + 1
    cells = _Cells.of(grid, fields.near_obstacle(tolerance), margin)
    out: list[MapSymmetry] = []
    for k in sorted({int(k) for k in orders if int(k) >= 2}, reverse=True):
        found = _order_symmetries(grid, cells, k, tolerance, least, min_overlap)
        for sym in found:
            logger.debug(
                "map symmetry: order %d about (%.2f, %.2f) m, overlap %.2f",
                k,
                sym.centre[0],
                sym.centre[1],
                sym.overlap,
            )
        out.extend(found)
    return out


#: Turns (2 pi / n) that a round map survives and no polygon of up to 12 sides does: a map that
#: overlaps itself turned by all of them about one centre is round (a circle, a circle with a
#: small piece of furniture), and its rotation about that centre is what laser SLAM never saw.
ROUND_TURNS = (13, 17, 19)


def round_centre(
    grid: OccupancyGrid,
    symmetries: list[MapSymmetry],
    *,
    tolerance: float = 0.05,
    min_overlap: float = 0.88,
) -> FloatArray | None:
    """The centre (2,) [m] about which ``grid`` is round, or None.

    A round map overlaps itself (at least ``min_overlap`` of its occupied cells within
    ``tolerance`` [m] of an occupied cell) turned by every one of :data:`ROUND_TURNS` about the
    centre of one of its whole-map ``symmetries`` (:func:`map_symmetries`) of order 7 or more,
    a centre a circle passes at every order. A regular polygon of up to 12 sides fails: the
    laser sees its rotation at its corners (a 9-gon of 2 m radius strays up to 12 cm from its
    circle, so ``tolerance`` is tighter than :func:`map_symmetries`' 0.1 m; rasterised dev
    and test worlds: circles overlap 0.92-0.99 turned, that 9-gon 0.63-0.75; its SLAM map of a
    dev trip 0.77-0.84, those of two dev circles and a circle with a box 0.92-1.00). In a round room neither the laser nor laser SLAM
    observes the rotation about the centre, so the map's rotation there is the mapping
    robot's gyro's (:attr:`symloc.localizer.claim.ClaimConfig.map_rotation_std`).

    A round room with furniture against its wall is round too: its furniture and the wall it
    hides break the whole-map overlap (a dev circle with a shelf: 0.87-0.90 turned), not the
    enclosing wall (:func:`_round_wall_share`). What pins such a room's rotation is a piece of
    furniture a metre or two wide, whose few centimetres of map error are degrees about the
    centre (that room's claims were 3.4 deg off with a heading std of 0.6 deg while it was
    judged not round).
    """
    check_positive(tolerance, "tolerance")
    centres = [s.centre for s in symmetries if not s.partial and s.order >= 7]
    if not centres or int(np.count_nonzero(grid.occupied_mask)) < 10:
        return None
    fields = MapFields.of(grid)
    margin = math.ceil(tolerance / grid.resolution) + 1
    cells = _Cells.of(fields.grid, fields.near_obstacle(tolerance), margin)
    for centre in centres:
        # a circle's centre is found only to the symmetry search's tolerance: refine it
        c, _ = _polish(fields.grid, cells, ROUND_TURNS[0], np.asarray(centre, float), tolerance)
        if all(_overlap(fields.grid, cells, n, c) >= min_overlap for n in ROUND_TURNS):
            return c
        if _round_wall_share(fields.grid, cells, c, min_overlap) >= ROUND_WALL_SHARE:
            return c
    return None


#: Share of the enclosing wall's :data:`WALL_SECTORS` sectors that must be round for a map to
#: be a round room with furniture (:func:`round_centre`): three quarters of its wall one
#: circle, the rest furniture against it, a door, what they hide. Dev SLAM maps: circles
#: (seeds 1-3) and circles with a pillar grid, a box or a shelf (furnished seeds 2, 7, 10)
#: 0.83-1.00; regular 8- to 11-gons (seeds 0, 2, 3, 5) 0.00-0.28.
ROUND_WALL_SHARE = 0.75
#: Equal angular sectors about the centre in which :func:`_round_wall_share` judges the wall.
WALL_SECTORS = 36


def _round_wall_share(
    grid: OccupancyGrid, cells: _Cells, centre: FloatArray, min_overlap: float
) -> float:
    """The share of :data:`WALL_SECTORS` sectors about ``centre`` (2,) [m] whose enclosing-wall
    cells land within the tolerance of an occupied cell (``cells.hits``) turned by every one of
    :data:`ROUND_TURNS`, at least ``min_overlap`` of them.

    The enclosing wall is, in each direction from the centre (bins one cell wide at the
    farthest cell), the occupied cells within 1.5 cells of the farthest: furniture standing
    free is inside it, furniture against the wall is where the wall is hidden. A polygon's
    wall fails in every sector (its corners and its edges' middles turn onto neither), a round
    wall with a shelf only where the shelf is and where its turned copies land.
    """
    d = cells.world - centre
    r = np.hypot(d[:, 0], d[:, 1])
    a = np.arctan2(d[:, 1], d[:, 0])
    bins = max(WALL_SECTORS, math.ceil(2.0 * math.pi * float(r.max()) / grid.resolution))
    b = _angle_bins(a, bins)
    farthest = np.full(bins, -np.inf)
    np.maximum.at(farthest, b, r)
    wall = r >= farthest[b] - 1.5 * grid.resolution
    wall_xy = cells.world[wall]
    round_cell = np.logical_and.reduce(
        [_landed_on_hits(grid, cells, wall_xy, n, centre) for n in ROUND_TURNS]
    )
    sector = _angle_bins(a[wall], WALL_SECTORS)
    total = np.bincount(sector, minlength=WALL_SECTORS)
    good = np.bincount(sector, weights=round_cell, minlength=WALL_SECTORS)
    share = np.divide(good, total, out=np.zeros(WALL_SECTORS), where=total > 0)
    return float(np.mean(share >= min_overlap))


def _angle_bins(angles: FloatArray, bins: int) -> IntArray:
    """The bin (N,) of each of ``angles`` (N,) [rad, in [-pi, pi]] among ``bins`` equal ones."""
    scaled = (np.asarray(angles) + math.pi) * (bins / (2.0 * math.pi))
    return np.minimum(scaled.astype(np.intp), bins - 1)


def _rotation(k: int) -> FloatArray:
    """The (2, 2) rotation by ``2 pi / k``."""
    a = 2.0 * math.pi / k
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s], [s, c]])


def _order_symmetries(
    grid: OccupancyGrid, cells: _Cells, k: int, tolerance: float, least: float, whole: float
) -> list[MapSymmetry]:
    """The centres (world [m]) about which turning by ``2 pi / k`` reaches an overlap of
    ``least``, best first; partial below ``whole``."""
    rot = _rotation(k)
    turned_f = cells.xy @ rot.T  # rounded in place: one float64 temporary, not three
    turned_f += 0.5
    np.floor(turned_f, out=turned_f)
    turned = turned_f.astype(np.intp)
    del turned_f
    need = math.ceil(least * cells.xy.shape[0] - 1e-9)
    # moving the centre by d [m] moves every turned cell by 2 sin(pi / k) d
    sep = 2.0 * math.sin(math.pi / k) * SEPARATION / grid.resolution
    to_centre = np.linalg.inv(np.eye(2) - rot)
    found: list[MapSymmetry] = []
    for shift in _best_shifts(cells, turned, need, sep):
        centre = _to_world(grid, to_centre @ shift + cells.offset)
        centre, share = _polish(grid, cells, k, centre, tolerance)
        if share < least or any(np.hypot(*(centre - f.centre)) < SEPARATION for f in found):
            continue
        if share < whole and not _free_at(grid, centre):
            continue  # a part of the map the robot is never in (beside a corridor, in a wall)
        found.append(MapSymmetry(centre=centre, order=k, overlap=share, partial=share < whole))
        if len(found) == MAX_CENTRES:
            break
    found.sort(key=lambda f: -f.overlap)
    return found


def _best_shifts(cells: _Cells, turned: IntArray, need: int, sep: float) -> list[FloatArray]:
    """Whole-cell shifts (x, y) of the ``turned`` cells (N, 2) that put at least ``need`` of
    them on the hits and are the best within ``sep`` cells, best first."""
    b = _coarsening(cells.hits.shape, turned)
    # most orders of most maps are ruled out on cells twice as coarse (a quarter of the work)
    counts, lo = _shift_counts(cells, turned, max(b, 2))
    if counts.size == 0 or float(counts.max()) < need:
        return []
    if b == 1:
        counts, lo = _shift_counts(cells, turned, 1)
    peaks = _local_maxima(counts, need, max(1, math.ceil(sep / b)))
    shifts = np.array([p + lo for p in peaks], dtype=np.intp).reshape(-1, 2)
    values = np.array([counts[p[1], p[0]] for p in peaks])
    if b > 1:
        shifts, values = _count_near_blocks(cells, turned, shifts, b, need)
    picked: list[IntArray] = []
    for i in np.argsort(-values, kind="stable"):
        s = shifts[i]
        if all(
            np.hypot(*(s - p)) > max(1.0, sep) and not _joined(counts, lo, b, s, p, values[i])
            for p in picked
        ):
            picked.append(s)
            if len(picked) == MAX_CENTRES + 2:
                break
    return [p.astype(np.float64) for p in picked]


def _local_maxima(counts: FloatArray, need: int, r: int) -> list[IntArray]:
    """Cells (column, row) of ``counts`` that reach ``need`` and are the largest within ``r``
    cells, best first, one per plateau, at most :data:`PEAKS`."""
    rows, cols = np.nonzero(counts >= need)
    if rows.size == 0:
        return []
    # a cell below ``need`` cannot top one above it: filter only around those above
    r0, c0 = max(int(rows.min()) - r, 0), max(int(cols.min()) - r, 0)
    part = counts[r0 : int(rows.max()) + r + 1, c0 : int(cols.max()) + r + 1]
    top = maximum_filter(part, size=2 * r + 1, mode="constant")
    rows, cols = np.nonzero((part >= need) & (part >= top))
    rows, cols = rows + r0, cols + c0
    out: list[IntArray] = []
    for i in np.argsort(-counts[rows, cols], kind="stable"):
        at = np.array([cols[i], rows[i]], dtype=np.intp)
        if all(np.abs(at - o).max() > r for o in out):
            out.append(at)
            if len(out) == PEAKS:
                break
    return out


def _count_near_blocks(
    cells: _Cells, turned: IntArray, blocks: IntArray, b: int, need: int
) -> tuple[IntArray, FloatArray]:
    """For each shift block (M, 2) (x, y) of ``b`` cells (a local maximum of the upper
    bounds): the best fine shift of it and its eight neighbours (the bound's maximum and the
    exact one need not share a block), counted exactly, and its count; those that reach
    ``need``."""
    size = 3 * b
    shifts, values = [], []
    for block in blocks:
        origin = b * (block - 1)
        counts = _window_counts(cells.hits, turned + origin, size)
        dy, dx = np.unravel_index(int(np.argmax(counts)), counts.shape)
        if counts[dy, dx] >= need:
            shifts.append(origin + np.array([dx, dy], dtype=np.intp))
            values.append(float(counts[dy, dx]))
    return np.array(shifts, dtype=np.intp).reshape(-1, 2), np.array(values)


def _window_counts(hits: BoolArray, cells: IntArray, size: int) -> FloatArray:
    """How many ``cells`` (N, 2) (x, y) land on ``hits`` (H, W) when shifted by each (dx, dy)
    in [0, size)^2: ``(size, size)`` counts indexed [dy, dx].

    The windows are gathered :data:`WINDOW_BYTES` at a time (N x size^2 bytes at once was
    gigabytes on a map of millions of occupied cells), or correlated by FFT
    (:func:`_window_counts_fft`) when that is over :data:`DIRECT_WINDOW_WORK` reads; the
    counts are whole numbers, so the sum in parts is the same sum."""
    h, w = hits.shape
    x, y = cells[:, 0], cells[:, 1]
    ok = (x >= -size) & (x <= w) & (y >= -size) & (y <= h)  # the window lies in the padding
    # (row, column) of each window's corner in the map padded by ``size`` on every side
    rows = y[ok].astype(np.int32)
    rows += size
    cols = x[ok].astype(np.int32)
    cols += size
    del ok
    if rows.size * size * size > DIRECT_WINDOW_WORK:
        return _window_counts_fft(hits, rows, cols, size)
    padded = np.zeros((h + 2 * size, w + 2 * size), dtype=np.uint8)
    padded[size : size + h, size : size + w] = hits
    windows = sliding_window_view(padded, (size, size))
    out: FloatArray = np.zeros((size, size))
    step = max(1, WINDOW_BYTES // (size * size))
    for i in range(0, rows.size, step):
        out += windows[rows[i : i + step], cols[i : i + step]].sum(axis=0, dtype=np.float64)
    return out


def _window_counts_fft(
    hits: BoolArray, rows: NDArray[np.int32], cols: NDArray[np.int32], size: int
) -> FloatArray:
    """:func:`_window_counts` by FFT, tile by tile: ``(size, size)`` counts indexed [dy, dx]
    of ``padded[rows + dy, cols + dx]`` summed over the cells, ``padded`` being ``hits``
    (H, W) with ``size`` cells of zeros on every side (each window inside it).

    The cells are binned into tiles of :data:`FFT_TILE` x :data:`FFT_TILE`; per tile, the
    correlation of its cell counts with the hits under it (the tile grown by ``size``) is one
    FFT product of side ``FFT_TILE + size`` (no wrap-around reaches the shifts kept). Sums of
    whole numbers below 2^31, rounded to them (float64 FFT error is orders below 1/2). For
    millions of cells and windows of hundreds of cells (an 8,192 x 8,192 office map) this is
    seconds where gathering each cell's window was hours."""
    h, w = hits.shape
    t = FFT_TILE
    side = next_fast_len(t + size, real=True)
    out: FloatArray = np.zeros((size, size))
    tile = rows // t
    tile *= (w + 2 * size) // t + 1
    tile += cols // t
    order = np.argsort(tile, kind="stable")
    starts = np.flatnonzero(np.diff(tile[order], prepend=-1))
    del tile
    for a, b in zip(starts, [*starts[1:], order.size], strict=True):
        sel = order[a:b]
        r0, c0 = (int(rows[sel[0]]) // t) * t, (int(cols[sel[0]]) // t) * t
        cells = np.zeros((t, t))
        np.add.at(cells, (rows[sel] - r0, cols[sel] - c0), 1.0)
        # the padded map's [r0, r0 + t + size) x [c0, c0 + t + size), read from ``hits``
        under = np.zeros((t + size, t + size))
        hr, hc = r0 - size, c0 - size  # where ``under`` starts in ``hits``
        a0, a1 = max(hr, 0), min(hr + t + size, h)
        b0, b1 = max(hc, 0), min(hc + t + size, w)
        if a1 > a0 and b1 > b0:
            under[a0 - hr : a1 - hr, b0 - hc : b1 - hc] = hits[a0:a1, b0:b1]
        spec = np.conj(rfft2(cells, s=(side, side))) * rfft2(under, s=(side, side))
        out += irfft2(spec, s=(side, side))[:size, :size]
    return np.rint(out)


def _joined(
    counts: FloatArray, lo: IntArray, b: int, a: IntArray, other: IntArray, value: float
) -> bool:
    """True when the straight path from shift ``a`` (2,) (x, y) to a better ``other`` never
    drops below :data:`RIDGE` x ``value`` (a's count) in ``counts`` (the counts of shift
    blocks of ``b`` cells from ``lo``, see :func:`_shift_counts`): a ridge, such as a
    corridor's centres along its axis, is one symmetry."""
    n = int(np.abs(other - a).max()) + 1
    path = np.floor_divide(np.rint(np.linspace(a, other, n)).astype(np.intp), b) - lo
    return bool(counts[path[:, 1], path[:, 0]].min() >= RIDGE * value)


def _coarsening(shape: tuple[int, ...], turned: IntArray) -> int:
    """The smallest power of two b whose b-times-coarser correlation fits MAX_FFT_CELLS."""
    span = turned.max(axis=0) - turned.min(axis=0) + 1
    b = 1
    while (shape[0] + span[1]) * (shape[1] + span[0]) > MAX_FFT_CELLS * b * b:
        b *= 2
    return b


def _coarse_hits(hits: BoolArray, b: int) -> BoolArray:
    """``hits`` (H, W) on cells ``b`` times coarser, each block also true where the next block
    up either axis (or both) holds a hit: a cell shifted by part of a block lands in its own
    block or the next one, so counting on these bounds every shift of a block from above.
    For ``b`` > 1 the answer starts one block early (its row and column 0 are block -1: a cell
    just below the map may land in it)."""
    if b == 1:
        return hits
    h, w = hits.shape
    padded = np.zeros((-(-h // b) * b + 2 * b, -(-w // b) * b + 2 * b), dtype=bool)
    padded[b : b + h, b : b + w] = hits
    blocks: BoolArray = np.asarray(
        padded.reshape(padded.shape[0] // b, b, padded.shape[1] // b, b).any(axis=(1, 3))
    )
    grown = blocks.copy()
    grown[:-1, :] |= blocks[1:, :]
    grown[:, :-1] |= grown[:, 1:].copy()
    return grown


def _shift_counts(cells: _Cells, turned: IntArray, b: int) -> tuple[FloatArray, IntArray]:
    """For every shift block (x, y) = ``lo`` + (column, row) of the answer: how many
    ``turned`` cells (N, 2) land on the hits when shifted by ``b`` x the block (``b`` = 1:
    exactly; else an upper bound for every shift ``b`` x block + [0, b) in each axis). Returns
    the counts (rows: y, columns: x) and ``lo`` (2,) (x, y)."""
    target = _coarse_hits(cells.hits, b).astype(np.float64)
    q = np.floor_divide(turned, b)
    qmin = q.min(axis=0)
    q = q - qmin
    kernel = np.zeros((int(q[:, 1].max()) + 1, int(q[:, 0].max()) + 1))
    np.add.at(kernel, (q[:, 1], q[:, 0]), 1.0)
    counts = np.rint(np.asarray(fftconvolve(target, kernel[::-1, ::-1], mode="full")))
    lo = -np.array([kernel.shape[1] - 1, kernel.shape[0] - 1], dtype=np.intp) - qmin
    return counts, lo - (b > 1)


def _to_world(grid: OccupancyGrid, xy: FloatArray) -> FloatArray:
    """Fractional (column, row) cell coordinates (2,) of the grid to a world point (2,) [m]."""
    world = grid.cell_to_world(np.array([[xy[1], xy[0]]]))
    return np.asarray(world, dtype=np.float64).reshape(2)


def _free_at(grid: OccupancyGrid, centre: FloatArray) -> bool:
    """True when a free cell lies within one cell of ``centre`` (2,) [m]."""
    r, c = (int(v) for v in np.asarray(grid.world_to_cell(centre[None, :]))[0])
    free = np.asarray(grid.free_mask, dtype=bool)[max(r - 1, 0) : r + 2, max(c - 1, 0) : c + 2]
    return bool(free.any())


def _overlap(grid: OccupancyGrid, cells: _Cells, k: int, centre: FloatArray) -> float:
    """Share of occupied cells that land on the hits when turned by ``2 pi / k`` about
    ``centre`` (2,) [m]."""
    n_on = 0
    for a in range(0, cells.world.shape[0], OVERLAP_CHUNK):  # bounded temporaries
        part = cells.world[a : a + OVERLAP_CHUNK]
        n_on += int(np.count_nonzero(_landed_on_hits(grid, cells, part, k, centre)))
    return n_on / cells.world.shape[0] if cells.world.shape[0] else float("nan")


def _landed_on_hits(
    grid: OccupancyGrid, cells: _Cells, points: FloatArray, k: int, centre: FloatArray
) -> BoolArray:
    """(N,) True where ``points`` (N, 2) [m] turned by ``2 pi / k`` about ``centre`` (2,) land
    on ``cells.hits`` (off the crop: False)."""
    landed = np.asarray(grid.world_to_cell(centre + (points - centre) @ _rotation(k).T))
    landed = landed - cells.offset[::-1]
    h, w = cells.hits.shape
    inside = (landed[:, 0] >= 0) & (landed[:, 0] < h) & (landed[:, 1] >= 0) & (landed[:, 1] < w)
    out = np.zeros(points.shape[0], dtype=bool)
    out[inside] = cells.hits[landed[inside, 0], landed[inside, 1]]
    return out


def _polish(
    grid: OccupancyGrid, cells: _Cells, k: int, centre: FloatArray, tolerance: float
) -> tuple[FloatArray, float]:
    """``centre`` (2,) [m] moved off the cell lattice by a local search (steps of half and a
    quarter of ``tolerance``) while the overlap grows; the centre and its overlap."""
    best = _overlap(grid, cells, k, centre)
    for step in (0.5 * tolerance, 0.25 * tolerance):
        improved = True
        while improved:
            improved = False
            for dx, dy in ((step, 0.0), (-step, 0.0), (0.0, step), (0.0, -step)):
                cand = centre + np.array([dx, dy])
                share = _overlap(grid, cells, k, cand)
                if share > best + 1e-9:
                    centre, best, improved = cand, share, True
    return centre, best
