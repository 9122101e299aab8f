"""Distance field and likelihood-field lookups on an occupancy grid.

The likelihood-field sensor model (Thrun, Burgard and Fox, *Probabilistic Robotics*, 2005,
Table 6.3; ROS amcl's ``map_update_cspace``) needs, for every cell, the distance [m] to the
nearest occupied cell, clipped at ``laser_likelihood_max_dist``. It is computed once per grid
with :func:`scipy.ndimage.distance_transform_edt` and cached.

Lookups go through a *padded* float32 table: the grid plus a one-cell border that holds the
clipped maximum, so any world point is one clip and one fancy index away from its value, and a
point off the map reads the maximum distance exactly as nav2_amcl does (``!MAP_VALID`` ->
``max_occ_dist``).
"""

from __future__ import annotations

import threading
import weakref
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.ndimage import binary_dilation, distance_transform_edt
from skimage.morphology import skeletonize

from symloc._checks import check_positive
from symloc.errors import ConfigurationError
from symloc.geometry import compose, inverse
from symloc.grid.occupancy_grid import OccupancyGrid

__all__ = [
    "DistanceField",
    "clear_distance_field_cache",
    "distance_field",
    "surface_distance_field",
]

FloatArray = NDArray[np.float64]

_CACHE: weakref.WeakKeyDictionary[OccupancyGrid, dict[float, DistanceField]] = (
    weakref.WeakKeyDictionary()
)
_SURFACE_CACHE: weakref.WeakKeyDictionary[OccupancyGrid, dict[float, DistanceField]] = (
    weakref.WeakKeyDictionary()
)
_LOCK = threading.Lock()


@dataclass(frozen=True, eq=False)
class DistanceField:
    """Distance [m] from each cell to the nearest occupied cell, clipped at ``max_dist``.

    Build it with :func:`distance_field` (cached per grid and ``max_dist``).

    Attributes
    ----------
    grid : OccupancyGrid
        The map it was computed from.
    max_dist : float
        Clip distance [m] (nav2's ``laser_likelihood_max_dist``).
    distances : ndarray of shape (H, W), float64
        Clipped distance [m] of each cell centre to the nearest occupied cell centre.
    padded : ndarray of shape (H + 2, W + 2), float32
        ``distances`` with a one-cell border of ``max_dist`` (off-map value).
    """

    grid: OccupancyGrid
    max_dist: float
    distances: FloatArray
    padded: NDArray[np.float32] = field(repr=False)
    _tables: dict[tuple[str, float, float, float, float], NDArray[np.float32]] = field(
        default_factory=dict, repr=False
    )

    @property
    def padded_width(self) -> int:
        """Number of columns of :attr:`padded` (W + 2)."""
        return int(self.padded.shape[1])

    def grid_frame_poses(self, poses: ArrayLike) -> FloatArray:
        """Poses ``(..., 3)`` from the map frame into the grid's own frame (origin removed).

        In the grid frame cell ``(row, col)`` covers ``[col, col+1) x [row, row+1)`` times the
        resolution.
        """
        p = np.asarray(poses, dtype=np.float64)
        o = self.grid.origin
        if o[2] == 0.0:
            out = p.copy()
            out[..., 0] -= o[0]
            out[..., 1] -= o[1]
            return out
        return compose(inverse(o), p)

    def padded_flat_index(
        self, x_cells: NDArray[np.floating], y_cells: NDArray[np.floating]
    ) -> NDArray[np.intp]:
        """Flat indices into ``padded.ravel()`` of points given in grid-frame *cell units*.

        ``x_cells = x_grid / resolution`` (so ``floor`` gives the column). Points off the map
        land on the border, which holds the off-map value. Inputs are modified in place
        (shifted by one and clipped) to avoid temporaries; pass arrays you own.
        """
        h2, w2 = self.padded.shape
        x_cells += 1.0
        y_cells += 1.0
        np.clip(x_cells, 0.0, w2 - 1, out=x_cells)
        np.clip(y_cells, 0.0, h2 - 1, out=y_cells)
        # After the shift every value is >= 0, so truncation equals floor.
        ix = x_cells.astype(np.intp)
        iy = y_cells.astype(np.intp)
        iy *= w2
        iy += ix
        return iy

    def lookup(self, points: ArrayLike) -> FloatArray:
        """Clipped distance [m] at world points ``(N, 2)``; ``max_dist`` off the map."""
        pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        poses = np.column_stack([pts, np.zeros(len(pts))])
        local = self.grid_frame_poses(poses)
        res = self.grid.resolution
        xs = local[:, 0] / res
        ys = local[:, 1] / res
        idx = self.padded_flat_index(xs, ys)
        return self.padded.ravel()[idx].astype(np.float64)

    def table(
        self, kind: str, z_hit: float, z_rand: float, sigma_hit: float, range_max: float
    ) -> NDArray[np.float32]:
        """A cached padded float32 table of a per-cell function of the distance.

        ``kind`` is ``"pz"`` for ``z_hit exp(-d^2 / 2 sigma^2) + z_rand / range_max``,
        ``"pz3"`` for its cube (nav2's likelihood field adds ``pz^3`` over beams) or
        ``"logpz"`` for its natural log (likelihood_field_prob). Flattened, shape
        ``((H + 2) * (W + 2),)``.
        """
        if kind not in ("pz", "pz3", "logpz"):
            raise ConfigurationError(f"kind: expected 'pz', 'pz3' or 'logpz', got {kind!r}")
        check_positive(sigma_hit, "sigma_hit")
        check_positive(range_max, "range_max")
        key = (kind, float(z_hit), float(z_rand), float(sigma_hit), float(range_max))
        tab = self._tables.get(key)
        if tab is None:
            d = self.padded.astype(np.float64)
            pz = z_hit * np.exp(-(d * d) / (2.0 * sigma_hit * sigma_hit)) + z_rand / range_max
            if kind == "pz3":
                pz = pz**3
            elif kind == "logpz":
                with np.errstate(divide="ignore"):
                    pz = np.log(pz)
            tab = np.ascontiguousarray(pz.ravel(), dtype=np.float32)
            tab.setflags(write=False)
            if len(self._tables) > 16:
                self._tables.clear()
            self._tables[key] = tab
        return tab


def _compute(grid: OccupancyGrid, max_dist: float) -> DistanceField:
    occ = grid.occupied_mask
    if occ.any():
        d = distance_transform_edt(~occ, sampling=grid.resolution)
        d = np.minimum(d, max_dist)
    else:
        d = np.full(occ.shape, max_dist)
    d = np.asarray(d, dtype=np.float64)
    d.setflags(write=False)
    padded = np.full((d.shape[0] + 2, d.shape[1] + 2), max_dist, dtype=np.float32)
    padded[1:-1, 1:-1] = d
    padded.setflags(write=False)
    return DistanceField(grid, max_dist, d, padded)


def distance_field(grid: OccupancyGrid, max_dist: float = 2.0) -> DistanceField:
    """The (cached) distance field of ``grid`` clipped at ``max_dist`` [m].

    Parameters
    ----------
    grid : OccupancyGrid
        Cells with occupancy above ``occupied_thresh`` are obstacles; unknown and free cells
        are not (as ROS amcl's ``map_update_cspace``).
    max_dist : float
        Clip distance [m] > 0, nav2's ``laser_likelihood_max_dist`` (default 2.0).

    Returns
    -------
    DistanceField
        Computed once per (grid, max_dist) and reused; the grid is immutable so the cache
        cannot go stale. A grid with no occupied cell gives ``max_dist`` everywhere.
    """
    if not isinstance(grid, OccupancyGrid):
        raise ConfigurationError(f"grid: expected an OccupancyGrid, got {type(grid).__name__}")
    md = check_positive(max_dist, "laser_likelihood_max_dist")
    with _LOCK:
        per_grid = _CACHE.setdefault(grid, {})
        df = per_grid.get(md)
        if df is None:
            df = _compute(grid, md)
            per_grid[md] = df
    return df


def _compute_surface(grid: OccupancyGrid, max_dist: float) -> DistanceField:
    occ = grid.occupied_mask
    free = grid.free_mask
    # the occupied cells that face free space (within two cells of it): a wall's band of hits
    # seen from the room, or the skin of a filled obstacle
    shell = occ & binary_dilation(free, iterations=2) if free.any() else occ
    centre: NDArray[np.bool_] = shell
    if shell.any():
        centre = np.asarray(skeletonize(shell), dtype=np.bool_)  # type: ignore[no-untyped-call]
    if centre.any():
        d = distance_transform_edt(~centre, sampling=grid.resolution)
        d = np.minimum(d, max_dist)
    else:
        d = np.full(occ.shape, max_dist)
    d = np.asarray(d, dtype=np.float64)
    d.setflags(write=False)
    padded = np.full((d.shape[0] + 2, d.shape[1] + 2), max_dist, dtype=np.float32)
    padded[1:-1, 1:-1] = d
    padded.setflags(write=False)
    return DistanceField(grid, max_dist, d, padded)


def surface_distance_field(grid: OccupancyGrid, max_dist: float = 1.0) -> DistanceField:
    """The (cached) distance [m] to the map's obstacle surfaces, as lines one cell thin.

    A laser map draws a wall as a band of occupied cells two or three cells thick (the hits
    of many scans straddle the surface), so the distance to the nearest occupied cell is zero
    across the whole band and says nothing about where in it the surface is. Here the band's
    cells that face free space are thinned to their centre line
    (:func:`skimage.morphology.skeletonize`) and the distance is measured to that line: zero
    on the surface's best estimate, with a gradient on both sides of it. Clipped at
    ``max_dist``; off the map reads ``max_dist``. Used by scan-to-map alignment
    (:mod:`symloc.mcl.scan_to_map`).
    """
    if not isinstance(grid, OccupancyGrid):
        raise ConfigurationError(f"grid: expected an OccupancyGrid, got {type(grid).__name__}")
    md = check_positive(max_dist, "max_dist")
    with _LOCK:
        per_grid = _SURFACE_CACHE.setdefault(grid, {})
        df = per_grid.get(md)
        if df is None:
            df = _compute_surface(grid, md)
            per_grid[md] = df
    return df


def clear_distance_field_cache() -> None:
    """Forget every cached distance field."""
    with _LOCK:
        _CACHE.clear()
        _SURFACE_CACHE.clear()
