"""Where a round robot fits in a room, and which of those places it can drive to.

:class:`FreeSpace` is a boolean grid of the cell centres where a robot of a given radius fits
(inside the room, clear of every static primitive whatever its height, not inside furniture),
labelled into connected components (8-connectivity). The *reachable* component is the one that
holds the room centre if the robot fits there, else the largest one: a robot set down anywhere
in it can drive to every other place in it. The grid only decides connectivity; whether an exact
point is free is always decided exactly by ``Room.is_free``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import ndimage
from skimage import draw

from symloc.sim.symmetry_truth import outline_samples
from symloc.sim.world import World

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
    boundary: ArrayLike,
    outlines: World,
    *,
    solids: Sequence[ArrayLike] = (),
    solid_circles: ArrayLike | None = None,
    resolution: float,
    clearance: float,
    center: ArrayLike,
) -> FreeSpace:
    """Rasterise a room and label where a robot of radius ``clearance`` [m] fits.

    Parameters
    ----------
    boundary : array of shape (V, 2)
        The room outline [m]; cells whose centres lie outside are blocked.
    outlines : World
        Every static primitive (of any height) whose outline the robot must keep clear of.
    solids : sequence of arrays of shape (K, 2)
        Filled obstacle footprints [m] (the robot cannot stand inside them).
    solid_circles : array of shape (C, 3), optional
        Filled round obstacles ``cx, cy, r`` [m].
    resolution : float
        Cell edge [m].
    clearance : float
        Robot radius [m].
    center : array of shape (2,)
        Picks the reachable component (see the module docstring).

    The distance of a cell to the nearest outline is the Euclidean distance transform of the
    rasterised outlines (plus the room outline), so it is exact to about one cell.
    """
    b = np.asarray(boundary, dtype=np.float64)
    res = float(resolution)
    xmin, ymin = b.min(axis=0) - 2 * res
    xmax, ymax = b.max(axis=0) + 2 * res
    w = max(1, int(np.ceil((xmax - xmin) / res)))
    h = max(1, int(np.ceil((ymax - ymin) / res)))
    origin = np.array([xmin, ymin])

    def to_cell(p: FloatArray) -> tuple[FloatArray, FloatArray]:
        return (p[:, 1] - ymin) / res - 0.5, (p[:, 0] - xmin) / res - 0.5

    inside = np.zeros((h, w), dtype=bool)
    rr, cc = to_cell(b)
    inside[draw.polygon(rr, cc, shape=(h, w))] = True  # type: ignore[no-untyped-call]
    for poly in solids:
        pr, pc = to_cell(np.asarray(poly, dtype=np.float64))
        inside[draw.polygon(pr, pc, shape=(h, w))] = False  # type: ignore[no-untyped-call]
    circles = (
        np.zeros((0, 3)) if solid_circles is None else np.asarray(solid_circles).reshape(-1, 3)
    )
    for cx, cy, r in circles:
        cr, ccol = to_cell(np.array([[cx, cy]]))
        inside[draw.disk((cr[0], ccol[0]), r / res, shape=(h, w))] = False  # type: ignore[no-untyped-call]
    ring = World(np.column_stack([b, np.roll(b, -1, axis=0)]))
    pts = np.concatenate([outline_samples(ring, res / 2)[0], outline_samples(outlines, res / 2)[0]])
    occupied = np.zeros((h, w), dtype=bool)
    pr, pc = to_cell(pts)
    ir = np.rint(pr).astype(np.int64)
    ic = np.rint(pc).astype(np.int64)
    ok = (ir >= 0) & (ir < h) & (ic >= 0) & (ic < w)
    occupied[ir[ok], ic[ok]] = True
    dist = ndimage.distance_transform_edt(~occupied) * res
    free = inside & (dist >= clearance)
    labels, n = ndimage.label(free, structure=np.ones((3, 3), dtype=bool))
    labels = labels.astype(np.int32)
    grid = FreeSpace(free, labels, 0, origin, res, float(clearance))
    main = 0
    if n:
        row, col = grid.cells(np.asarray(center, dtype=np.float64)[None])
        if 0 <= row[0] < h and 0 <= col[0] < w:
            main = int(labels[row[0], col[0]])
        if main == 0:
            main = int(np.argmax(np.bincount(labels.ravel())[1:])) + 1
    for arr in (free, labels):
        arr.setflags(write=False)
    return FreeSpace(free, labels, main, origin, res, float(clearance))
