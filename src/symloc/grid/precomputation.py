"""Precomputation grids for branch-and-bound scan matching (Hess et al. 2016, Section V.C).

A scan end point *hits* a cell when the cell's centre lies within ``tolerance`` [m] of the
centre of an occupied cell. Level 0 is that hit mask; level ``d`` holds, at cell ``(r, c)``,
the maximum of level 0 over the ``2^d x 2^d`` cells ``[r, r + 2^d) x [c, c + 2^d)`` (the
window *starts* at the cell, as Cartographer's ``PrecomputationGrid2D``). Summing level ``d``
at a scan's end points for the corner translation of a block of ``2^d x 2^d`` translations
bounds the number of hits of every translation in the block: the bound that lets the search
prune a block without missing any pose in it.

All levels share one array, ``bits`` ``(H + 2P, W + 2P)`` with ``P = 2^depth``: level ``d`` is
bit ``d`` of each entry, map cell ``(r, c)`` at index ``(r + P, c + P)``; the border is zero at
level 0, so an end point off the map hits nothing and an index outside the array reads 0 at
every level. Memory: 1 byte per padded cell up to depth 7 (Cartographer's default; a level
per byte was 8), 2 beyond. Built once per map and
tolerance through :meth:`symloc.grid.fields.MapFields.precomputation_grids`, with the integral
image of the free cells (where a robot may stand) that tells a block with no free cell apart.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from symloc.errors import ConfigurationError

__all__ = ["MAX_DEPTH", "PrecomputationGrids", "build_precomputation_grids"]

#: Deepest pyramid built (blocks of 4,096 x 4,096 cells).
MAX_DEPTH = 12


@dataclass(frozen=True, slots=True, eq=False)
class PrecomputationGrids:
    """The max-pooled hit pyramid of one map and the integral image of its free cells.

    Attributes
    ----------
    bits : ndarray of shape (H + 2 pad, W + 2 pad), uint8 (uint16 for depth > 7)
        Bit ``d`` at index ``(r + pad, c + pad)`` (level ``d``): 1 if any cell of ``[r, r +
        2^d) x [c, c + 2^d)`` is a hit (read-only); :meth:`level` unpacks one level.
    free_integral : ndarray of shape (H + 1, W + 1), int32
        ``free_integral[r, c]`` = free cells in rows ``< r`` and columns ``< c`` (read-only).
    depth : int
    pad : int
        ``2^depth``.
    tolerance : float
        Hit tolerance [m].
    height, width : int
        The map's shape.
    """

    bits: NDArray[np.unsignedinteger]
    free_integral: NDArray[np.int32]
    depth: int
    pad: int
    tolerance: float
    height: int
    width: int

    @property
    def nbytes(self) -> int:
        """Memory held [bytes]."""
        return int(self.bits.nbytes + self.free_integral.nbytes)

    def level(self, d: int) -> NDArray[np.uint8]:
        """Level ``d`` (0 .. depth) as its own ``(H + 2 pad, W + 2 pad)`` uint8 array of 0 and 1
        (a new array: for tests and figures, the search reads :attr:`bits`)."""
        if not 0 <= d <= self.depth:
            raise ConfigurationError(f"d: expected a level in [0, {self.depth}], got {d}")
        return ((self.bits >> d) & 1).astype(np.uint8)

    def free_count(self, r0: int, r1: int, c0: int, c1: int) -> int:
        """Free cells in rows ``[r0, r1)`` and columns ``[c0, c1)`` (clipped to the map)."""
        r0, r1 = max(r0, 0), min(r1, self.height)
        c0, c1 = max(c0, 0), min(c1, self.width)
        if r0 >= r1 or c0 >= c1:
            return 0
        f = self.free_integral
        return int(f[r1, c1]) - int(f[r0, c1]) - int(f[r1, c0]) + int(f[r0, c0])


def build_precomputation_grids(
    near: NDArray[np.bool_],
    occupied: NDArray[np.bool_],
    free: NDArray[np.bool_],
    tolerance: float,
    depth: int,
) -> PrecomputationGrids:
    """The pyramid of a map from its cells near an obstacle ``(H, W)``.

    Parameters
    ----------
    near : array of shape (H, W), bool
        The cells whose centre lies within ``tolerance`` of an occupied cell's centre
        (:meth:`~symloc.grid.fields.MapFields.near_obstacle`).
    occupied, free : array of shape (H, W), bool
        The map's occupied and free cells (a map with no occupied cell hits nothing).
    tolerance : float
        Hit tolerance [m] (>= 0) ``near`` was made with (kept on the result).
    depth : int
        Levels above level 0, in ``[0, MAX_DEPTH]``.
    """
    if not isinstance(depth, (int, np.integer)) or isinstance(depth, bool):
        raise ConfigurationError(f"depth: expected an integer, got {depth!r}")
    if not 0 <= depth <= MAX_DEPTH:
        raise ConfigurationError(f"depth: expected an integer in [0, {MAX_DEPTH}], got {depth}")
    near = np.asarray(near, dtype=bool)
    h, w = near.shape
    pad = 1 << int(depth)
    dtype = np.uint8 if depth < 8 else np.uint16
    bits = np.zeros((h + 2 * pad, w + 2 * pad), dtype=dtype)
    cur = np.zeros_like(bits)  # one level at a time
    if np.any(occupied):
        cur[pad : pad + h, pad : pad + w] = near
    bits |= cur
    for d in range(1, depth + 1):
        s = 1 << (d - 1)
        # (ufuncs read overlapping operands as if copied first: each step sees the level below)
        np.maximum(cur[:-s, :], cur[s:, :], out=cur[:-s, :])
        np.maximum(cur[:, :-s], cur[:, s:], out=cur[:, :-s])
        bits |= cur << dtype(d)
    del cur
    bits.setflags(write=False)
    integral = _integral_image(np.asarray(free, dtype=bool))
    integral.setflags(write=False)
    return PrecomputationGrids(bits, integral, int(depth), pad, float(tolerance), h, w)


#: Rows of the integral image summed at a time (bounds the temporaries).
_INTEGRAL_ROWS = 256


def _integral_image(free: NDArray[np.bool_]) -> NDArray[np.int32]:
    """``(H + 1, W + 1)`` int32: entry ``[r, c]`` counts the ``free`` cells above and left of
    ``(r, c)`` (row and column 0 are zero).

    Summed in place, a band of rows at a time: ``np.cumsum`` of an int32 array makes int64
    temporaries of the whole map (16 bytes per cell with the int32 input); here the peak is
    the result's 4 bytes per cell. At most 2^31 - 1 cells (the map file cap is 2^26)."""
    h, w = free.shape
    integral = np.zeros((h + 1, w + 1), dtype=np.int32)
    for a in range(0, h, _INTEGRAL_ROWS):
        band = integral[1 + a : 1 + a + _INTEGRAL_ROWS, 1:]
        np.cumsum(free[a : a + _INTEGRAL_ROWS], axis=1, dtype=np.int32, out=band)
        np.cumsum(band, axis=0, dtype=np.int32, out=band)
        band += integral[a, 1:]  # the count of every row above the band
    return integral
