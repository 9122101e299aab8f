"""Where a round robot fits in a room, and which of those places it can drive to.

:class:`FreeSpace` is a boolean grid of the cell centres where a robot of a given radius fits
(inside the room, clear of every static primitive whatever its height, not inside furniture),
labelled into connected components (8-connectivity). The *reachable* component is the one that
holds the room centre if the robot fits there, else the largest one: a robot set down anywhere
in it can drive to every other place in it. The grid only decides connectivity; whether an exact
point is free is always decided exactly by ``Room.is_free``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage

__all__ = ["FreeSpace", "free_space_grid"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class FreeSpace:
    """Free cells and their connected components.

    Attributes
    ----------
    free : ndarray of shape (H, W), bool
        True where a robot of radius ``clearance`` fits at the cell centre; row i is
        y = origin[1] + (i + 0.5) * resolution, column j is x = origin[0] + (j + 0.5) * resolution.
    labels : ndarray of shape (H, W), int
        Component of each free cell (1..), 0 for blocked cells.
    reachable_label : int
        The component the robot can drive in (0 if nothing is free).
    origin : ndarray of shape (2,)
        World position [m] of the grid's lower-left corner.
    resolution : float
        Cell edge [m].
    clearance : float
        Robot radius [m] the grid was built for.
    """

    free: NDArray[np.bool_]
    labels: NDArray[np.int32]
    reachable_label: int
    origin: FloatArray
    resolution: float
    clearance: float

    @property
    def free_area(self) -> float:
        """Area [m^2] of all free cells."""
        return float(np.count_nonzero(self.free)) * self.resolution**2

    @property
    def reachable_area(self) -> float:
        """Area [m^2] of the reachable component."""
        if self.reachable_label == 0:
            return 0.0
        return float(np.count_nonzero(self.labels == self.reachable_label)) * self.resolution**2

    @property
    def n_components(self) -> int:
        """Number of separate free regions."""
        return int(self.labels.max())

    def cells(self, points: ArrayLike) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
        """Row and column ``(N,)`` of points ``(N, 2)`` [m] (may fall outside the grid)."""
        p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        col = np.floor((p[:, 0] - self.origin[0]) / self.resolution).astype(np.int64)
        row = np.floor((p[:, 1] - self.origin[1]) / self.resolution).astype(np.int64)
        return row, col

    def in_reachable(self, points: ArrayLike) -> NDArray[np.bool_]:
        """``(N,)`` True where a point's cell or one of its 8 neighbours is reachable.

        Meant for points already known to be free: the neighbours cover a free point whose cell
        centre is a few millimetres too close to a wall.
        """
        row, col = self.cells(points)
        h, w = self.labels.shape
        out = np.zeros(row.shape[0], dtype=bool)
        if self.reachable_label == 0:
            return out
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                r, c = row + dr, col + dc
                ok = (r >= 0) & (r < h) & (c >= 0) & (c < w)
                lab = np.zeros(row.shape[0], dtype=np.int64)
                lab[ok] = self.labels[r[ok], c[ok]]
                out |= lab == self.reachable_label
        return out


def free_space_grid(
    is_free: Callable[[FloatArray], NDArray[np.bool_]],
    bounds: tuple[float, float, float, float],
    *,
    resolution: float,
    clearance: float,
    center: ArrayLike,
) -> FreeSpace:
    """Evaluate ``is_free`` on a grid over ``bounds`` = (xmin, xmax, ymin, ymax) [m] and label it.

    ``center`` picks the reachable component (see the module docstring).
    """
    xmin, xmax, ymin, ymax = bounds
    w = max(1, int(np.ceil((xmax - xmin) / resolution)))
    h = max(1, int(np.ceil((ymax - ymin) / resolution)))
    xs = xmin + (np.arange(w) + 0.5) * resolution
    ys = ymin + (np.arange(h) + 0.5) * resolution
    gx, gy = np.meshgrid(xs, ys)
    free = is_free(np.column_stack([gx.ravel(), gy.ravel()])).reshape(h, w)
    labels, n = ndimage.label(free, structure=np.ones((3, 3), dtype=bool))
    labels = labels.astype(np.int32)
    grid = FreeSpace(
        free=free,
        labels=labels,
        reachable_label=0,
        origin=np.array([xmin, ymin]),
        resolution=float(resolution),
        clearance=float(clearance),
    )
    if n == 0:
        return grid
    row, col = grid.cells(np.asarray(center, dtype=np.float64)[None])
    main = 0
    if 0 <= row[0] < h and 0 <= col[0] < w:
        main = int(labels[row[0], col[0]])
    if main == 0:
        sizes = np.bincount(labels.ravel())[1:]
        main = int(np.argmax(sizes)) + 1
    for arr in (free, labels):
        arr.setflags(write=False)
    return FreeSpace(free, labels, main, grid.origin, grid.resolution, grid.clearance)
