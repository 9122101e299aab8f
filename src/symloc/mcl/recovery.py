"""Augmented MCL recovery: random particle injection (Thrun et al. 2005, Table 8.3).

The filter tracks a short-term and a long-term average of the mean particle likelihood,
``w_fast`` and ``w_slow`` (smoothing ``recovery_alpha_fast`` > ``recovery_alpha_slow``). When
the short-term average drops below the long-term one, each resampled particle is replaced by a
pose drawn uniformly over the free cells with probability ``max(0, 1 - w_fast / w_slow)``. As
in amcl, both averages are reset after an injection.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from symloc.errors import ConfigurationError
from symloc.grid.occupancy_grid import OccupancyGrid

__all__ = ["FreeSpaceSampler", "RecoveryState"]

FloatArray = NDArray[np.float64]


@dataclass
class RecoveryState:
    """The two running averages of the mean likelihood (amcl's ``w_slow`` / ``w_fast``)."""

    alpha_slow: float
    alpha_fast: float
    w_slow: float = 0.0
    w_fast: float = 0.0

    def observe(self, w_avg: float) -> None:
        """Fold in the mean (un-normalised) particle likelihood of one sensor update."""
        if not np.isfinite(w_avg) or w_avg < 0:
            return
        self.w_slow = (
            w_avg if self.w_slow == 0.0 else self.w_slow + self.alpha_slow * (w_avg - self.w_slow)
        )
        self.w_fast = (
            w_avg if self.w_fast == 0.0 else self.w_fast + self.alpha_fast * (w_avg - self.w_fast)
        )

    def injection_probability(self) -> float:
        """``max(0, 1 - w_fast / w_slow)``; 0 while recovery is off or nothing was seen."""
        if self.alpha_slow <= 0.0 or self.alpha_fast <= 0.0 or self.w_slow <= 0.0:
            return 0.0
        return max(0.0, 1.0 - self.w_fast / self.w_slow)

    def reset(self) -> None:
        """Forget both averages (after an injection, as amcl)."""
        self.w_slow = 0.0
        self.w_fast = 0.0


#: Cells per block of the free-cell counts :class:`FreeSpaceSampler` draws through.
FREE_BLOCK = 64


class FreeSpaceSampler:
    """Poses uniform over the free cells of a grid (position uniform inside each cell).

    Raises :class:`~symloc.errors.ConfigurationError` if the grid has no free cell. A draw
    picks the k-th free cell (row-major) for uniform k, found through the count of free cells
    before each block of :data:`FREE_BLOCK` cells (built on the first draw, 8 bytes per block:
    8 MiB for the 8,192^2 map file cap, where the list of free cells was 4 bytes per free
    cell, about 240 MiB), so a filter that only tracks never holds it.
    """

    def __init__(self, grid: OccupancyGrid) -> None:
        n_free = int(np.count_nonzero(grid.free_mask))
        if n_free == 0:
            raise ConfigurationError(
                "grid: the map has no free cell (occupancy < free_thresh), so particles cannot"
                " be spread over free space"
            )
        self.grid = grid
        self.n_free = n_free
        self._free_cells: NDArray[np.signedinteger[Any]] | None = None
        self._before_block: NDArray[np.int64] | None = None

    @property
    def free_cells(self) -> NDArray[np.signedinteger[Any]]:
        """Flat indices of the free cells (row-major), ascending."""
        if self._free_cells is None:
            g = self.grid
            if g.data.size >= 2**31:
                self._free_cells = np.flatnonzero(g.free_mask.ravel())
            else:  # row blocks: no map-sized int64 temporary
                out = np.empty(self.n_free, dtype=np.int32)
                rows = max(1, (1 << 22) // max(1, g.width))
                k = 0
                for r in range(0, g.height, rows):
                    d = g.data[r : r + rows]
                    idx = np.flatnonzero(g.is_free(d))
                    out[k : k + idx.size] = idx + r * g.width
                    k += idx.size
                self._free_cells = out
        return self._free_cells

    def _free_flags(self, flat: NDArray[np.int8]) -> NDArray[np.bool_]:
        """Free (as :attr:`OccupancyGrid.free_mask`) flags of some of the grid's cells."""
        return self.grid.is_free(flat)

    def _block_starts(self) -> NDArray[np.int64]:
        """``(n_blocks + 1,)``: free cells before each block of :data:`FREE_BLOCK` cells of the
        row-major grid (and, last, all of them); counted a few MiB of cells at a time."""
        if self._before_block is None:
            flat = self.grid.data.reshape(-1)
            n_blocks = -(-flat.size // FREE_BLOCK)
            out = np.zeros(n_blocks + 1, dtype=np.int64)
            step = FREE_BLOCK * 65536
            for a in range(0, flat.size, step):
                f = self._free_flags(flat[a : a + step])
                m = -(-f.size // FREE_BLOCK)
                padded = np.zeros(m * FREE_BLOCK, dtype=bool)
                padded[: f.size] = f
                b = a // FREE_BLOCK
                out[1 + b : 1 + b + m] = padded.reshape(m, FREE_BLOCK).sum(axis=1)
            np.cumsum(out, out=out)
            self._before_block = out
        return self._before_block

    def nth_free(self, k: NDArray[np.integer[Any]]) -> NDArray[np.int64]:
        """Flat (row-major) indices ``(n,)`` of the ``k``-th free cells (``k`` ``(n,)`` in
        ``[0, n_free)``): ``free_cells[k]``, without the list."""
        before = self._block_starts()
        k = np.asarray(k, dtype=np.int64)
        block = np.searchsorted(before, k, side="right") - 1
        j = k - before[block]  # the j-th free cell of its block
        cells = block[:, None] * FREE_BLOCK + np.arange(FREE_BLOCK)
        flat = self.grid.data.reshape(-1)
        inside = cells < flat.size
        free = self._free_flags(flat[np.minimum(cells, flat.size - 1)]) & inside
        seen = np.cumsum(free, axis=1)
        return np.asarray(cells[np.arange(k.size), np.argmax(seen > j[:, None], axis=1)])

    def sample(self, n: int, rng: np.random.Generator) -> FloatArray:
        """``(n, 3)`` poses x [m], y [m], theta [rad] in the map frame."""
        if n < 0:
            raise ConfigurationError(f"n: expected a count >= 0, got {n}")
        g = self.grid
        pick = self.nth_free(rng.integers(0, self.n_free, size=n))
        rows, cols = np.divmod(pick, g.width)
        jitter = rng.random((n, 2))
        lx = (cols + jitter[:, 0]) * g.resolution
        ly = (rows + jitter[:, 1]) * g.resolution
        c, s = np.cos(g.origin[2]), np.sin(g.origin[2])
        out = np.empty((n, 3))
        out[:, 0] = g.origin[0] + c * lx - s * ly
        out[:, 1] = g.origin[1] + s * lx + c * ly
        out[:, 2] = rng.uniform(-np.pi, np.pi, size=n)
        return out
