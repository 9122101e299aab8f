"""``MapFields``: every field of one map, computed lazily once and shared by every consumer.

The parts that localize on a map each need a field derived from it: AMCL's likelihood field
(the distance to the nearest occupied cell clipped at ``laser_likelihood_max_dist``), the
confidence check's wider distance field, the rival search's field on the map grown by a border
of unknown cells, the beam model's distance to the nearest non-free cell, the pose scorer's and
the map-symmetry search's unclipped distance, the claim gate's distance to the walls'
centre lines, and the global search's branch-and-bound precomputation grids.
``MapFields.of(grid)`` is the one cache of them for a grid: each field is
computed the first time a consumer asks and then handed to every other consumer of the same
grid object. The cache lives on the grid (its lifetime is the grid's; nothing global keeps a
map alive) and is left out when the grid is pickled or copied.

Every consumer (``Amcl``, ``GridScorer``, ``map_symmetries``, the beam model, the rival
search) accepts either an :class:`~symloc.grid.OccupancyGrid` or its ``MapFields``.
"""

from __future__ import annotations

import math
import threading
from collections import Counter
from collections.abc import Callable
from typing import Any, TypeVar, cast

import cv2
import numpy as np
from numpy.typing import NDArray

from symloc._checks import check_positive
from symloc.errors import ConfigurationError
from symloc.geometry import compose
from symloc.grid.distance_field import (
    DistanceField,
    compute_distance_field,
    compute_surface_distance_field,
    grown_padded_distances,
)
from symloc.grid.occupancy_grid import OccupancyGrid
from symloc.grid.precomputation import PrecomputationGrids, build_precomputation_grids

__all__ = [
    "MapFields",
    "clear_distance_field_cache",
    "distance_field",
    "surface_distance_field",
]

#: The attribute of an OccupancyGrid that holds its MapFields (see OccupancyGrid.__getstate__).
_ATTR = "_map_fields"
_OF_LOCK = threading.Lock()

T = TypeVar("T")


class MapFields:
    """The fields of one map, each computed on first use and then shared.

    Get the one instance of a grid with :meth:`of`; constructing one directly gives a private
    cache (what a test that counts computations wants).

    Parameters
    ----------
    grid : OccupancyGrid
        The map (immutable, so no field can go stale).

    Attributes
    ----------
    grid : OccupancyGrid
    n_computed : collections.Counter of str
        How many times each kind of field was computed (``"distance"``, ``"surface"``,
        ``"grown"``, ``"obstacle_distance"``, ``"blocked_distance"``, ``"precomputation"``, and
        the name of each :meth:`derived` value): with one shared cache each distinct field is
        computed once.
    """

    def __init__(self, grid: OccupancyGrid) -> None:
        if not isinstance(grid, OccupancyGrid):
            raise ConfigurationError(f"grid: expected an OccupancyGrid, got {type(grid).__name__}")
        self.grid = grid
        self.n_computed: Counter[str] = Counter()
        self._lock = threading.RLock()
        self._distance: dict[float, DistanceField] = {}
        self._surface: dict[float, DistanceField] = {}
        self._grown: dict[float, DistanceField] = {}
        self._obstacle: NDArray[np.float64] | None = None
        self._obstacle_k: NDArray[np.uint16] | None = None
        self._obstacle_m: NDArray[np.float64] | None = None
        self._blocked: NDArray[np.float32] | None = None
        self._pyramids: dict[tuple[float, int], PrecomputationGrids] = {}
        self._derived: dict[str, object] = {}

    @classmethod
    def of(cls, source: OccupancyGrid | MapFields) -> MapFields:
        """The shared fields of ``source`` (a grid, or its fields returned as they are).

        The cache is stored on the grid object itself, so every consumer built on the same
        grid object shares it and it dies with the grid.
        """
        if isinstance(source, MapFields):
            return source
        if not isinstance(source, OccupancyGrid):
            raise ConfigurationError(
                f"grid: expected an OccupancyGrid or MapFields, got {type(source).__name__}"
            )
        fields = source.__dict__.get(_ATTR)
        if fields is None:
            with _OF_LOCK:
                fields = source.__dict__.get(_ATTR)
                if fields is None:
                    fields = cls(source)
                    object.__setattr__(source, _ATTR, fields)  # frozen dataclass: a cache only
        assert isinstance(fields, MapFields)
        return fields

    # ------------------------------------------------------------------ fields
    def distance(self, max_dist: float = 2.0) -> DistanceField:
        """Distance [m] to the nearest occupied cell clipped at ``max_dist`` [m] > 0.

        AMCL's likelihood field (``max_dist`` is nav2's ``laser_likelihood_max_dist``) and the
        confidence check's scan-consistency field. Cells with occupancy above
        ``occupied_thresh`` are obstacles; unknown and free cells are not (as ROS amcl's
        ``map_update_cspace``); off the map reads ``max_dist``; a grid with no occupied cell
        gives ``max_dist`` everywhere. Its per-cell likelihood tables
        (:meth:`DistanceField.table`) are cached on it, so they are shared too.
        """
        md = check_positive(max_dist, "laser_likelihood_max_dist")
        with self._lock:
            df = self._distance.get(md)
            if df is None:
                df = compute_distance_field(self.grid, md)
                self.n_computed["distance"] += 1
                self._distance[md] = df
        return df

    def surface(self, max_dist: float = 1.0) -> DistanceField:
        """Distance [m] to the map's obstacle surfaces, as lines one cell thin.

        A laser map draws a wall as a band of occupied cells two or three cells thick (the hits
        of many scans straddle the surface), so the distance to the nearest occupied cell is
        zero across the whole band and says nothing about where in it the surface is. Here the
        band's cells that face free space are thinned to their centre line
        (:func:`skimage.morphology.skeletonize`) and the distance is measured to that line:
        zero on the surface's best estimate, with a gradient on both sides of it. Clipped at
        ``max_dist`` [m] > 0; off the map reads ``max_dist``. Used by scan-to-map alignment
        (:mod:`symloc.mcl.scan_to_map`) and the localizer's claim gate.
        """
        md = check_positive(max_dist, "max_dist")
        with self._lock:
            df = self._surface.get(md)
            if df is None:
                df = compute_surface_distance_field(self.grid, md)
                self.n_computed["surface"] += 1
                self._surface[md] = df
        return df

    def grown(self, max_dist: float) -> DistanceField:
        """:meth:`distance` of the map grown by ``max_dist`` [m] of unknown cells on every side.

        Same frame and free cells as the map; its grid is a new, larger object (kept alive by
        the field). The rival search (:mod:`symloc.mcl.rival_search`) reads it so that a
        candidate pose near the map's edge scores its points off the map as far away.
        """
        md = check_positive(max_dist, "max_dist")
        with self._lock:
            df = self._grown.get(md)
            if df is None:
                g = self.grid
                pad = math.ceil(md / g.resolution) + 1
                data = np.pad(g.data, pad, constant_values=-1)
                origin = compose(
                    np.asarray(g.origin, dtype=np.float64), [-pad * g.resolution] * 2 + [0]
                )
                big = OccupancyGrid(data, g.resolution, origin, g.occupied_thresh, g.free_thresh)
                own = self._distance.get(md)
                if own is None:
                    df = compute_distance_field(big, md)
                else:  # the map's own field is there (AMCL's): only the margin is new
                    padded = grown_padded_distances(
                        own.padded, g.occupied_mask, pad, g.resolution, md
                    )
                    padded.setflags(write=False)
                    df = DistanceField(big, md, padded)
                self.n_computed["grown"] += 1
                self._grown[md] = df
        return df

    def obstacle_distance(self) -> NDArray[np.float64]:
        """Unclipped distance [m] of each cell ``(H, W)`` to the nearest occupied cell, float64.

        The values of :func:`scipy.ndimage.distance_transform_edt` of the free-of-obstacle
        mask times the resolution (read-only), computed by :func:`_obstacle_distance` with
        a third of its memory. Read by the localizer's pose scorer
        (:class:`symloc.localizer.adapters.GridScorer`), the global search and
        :func:`symloc.localizer.map_symmetry.map_symmetries`.
        """
        with self._lock:
            if self._obstacle is None:
                dist = _obstacle_distance(self.grid.occupied_mask, self.grid.resolution)
                dist.setflags(write=False)
                self._obstacle = dist
                self.n_computed["obstacle_distance"] += 1
            return self._obstacle

    def obstacle_squared_cells(self) -> tuple[NDArray[np.uint16], NDArray[np.float64]]:
        """The obstacle distance in 2 bytes per cell: ``(k, metres)``.

        ``k`` ``(H, W)`` uint16 (read-only) is each cell's squared distance ``dx^2 + dy^2``
        [cells^2] to the nearest occupied cell, clipped at :data:`OBSTACLE_K_MAX` (farther,
        or a map without an occupied cell); ``metres`` ``(OBSTACLE_K_MAX + 1,)`` float64 maps
        it to metres: ``metres[k]`` equals :meth:`obstacle_distance` value for value wherever
        ``k < OBSTACLE_K_MAX``, and ``metres[OBSTACLE_K_MAX]`` (:meth:`obstacle_reach`) is a
        lower bound elsewhere. The consumers that only need the distance up to some cap (the
        global search, the pose scorer, the hit masks) read this, a quarter of the float64
        field (the 8,192^2 map file cap: 134 MB instead of 537 MB, and no float64 ever).
        """
        with self._lock:
            if self._obstacle_k is None:
                k = _obstacle_squared_cells(self.grid.occupied_mask)
                k.setflags(write=False)
                metres = np.sqrt(np.arange(OBSTACLE_K_MAX + 1, dtype=np.float64))
                metres *= self.grid.resolution
                metres.setflags(write=False)
                self._obstacle_k, self._obstacle_m = k, metres
                self.n_computed["obstacle_squared_cells"] += 1
            assert self._obstacle_m is not None
            return self._obstacle_k, self._obstacle_m

    def obstacle_reach(self) -> float:
        """Distance [m] up to which :meth:`obstacle_squared_cells` is exact:
        ``sqrt(OBSTACLE_K_MAX)`` cells (about 256)."""
        return math.sqrt(OBSTACLE_K_MAX) * self.grid.resolution

    def near_obstacle(self, tolerance: float) -> NDArray[np.bool_]:
        """``(H, W)`` bool: cells whose centre lies within ``tolerance`` [m] (>= 0) of an occupied
        cell's centre: ``obstacle_distance() <= tolerance``, read from the 2-byte field when the
        tolerance is below :meth:`obstacle_reach` and the map has an occupied cell. A new array
        each call."""
        tol = check_positive(tolerance, "tolerance", allow_zero=True)
        if tol >= self.obstacle_reach() or not self.grid.occupied_mask.any():
            # (scipy's transform of a map without an occupied cell measures from outside it)
            return np.asarray(self.obstacle_distance() <= tol)
        k, metres = self.obstacle_squared_cells()
        near_k = metres <= tol  # monotone in k: the near ones are k <= some k_tol
        k_tol = int(np.count_nonzero(near_k)) - 1
        return np.asarray(k <= k_tol)

    def blocked_distance(self) -> NDArray[np.float32]:
        """Distance [m] to the nearest non-free cell, padded ``(H + 2, W + 2)`` float32.

        The one-cell border counts as non-free (0), so a ray leaving the map stops there. The
        beam model's sphere tracing (:func:`symloc.mcl.beam_model.raycast_grid`) reads it.
        """
        with self._lock:
            if self._blocked is None:
                g = self.grid
                free = np.zeros((g.height + 2, g.width + 2), dtype=bool)
                free[1:-1, 1:-1] = g.free_mask
                tab = distance_transform_edt(free, sampling=g.resolution).astype(np.float32)
                tab.setflags(write=False)
                self._blocked = tab
                self.n_computed["blocked_distance"] += 1
            return self._blocked

    def precomputation_grids(self, tolerance: float, depth: int) -> PrecomputationGrids:
        """The branch-and-bound precomputation grids of the map (``"precomputation"``).

        Level 0 marks the cells within ``tolerance`` [m] (>= 0) of an occupied cell (read from
        :meth:`obstacle_distance`); level ``d <= depth`` is its max over ``2^d x 2^d`` blocks;
        with the integral image of the free cells. Read by the global scan-to-map search
        (:mod:`symloc.mcl.global_search`); see :mod:`symloc.grid.precomputation`.
        """
        tol = check_positive(tolerance, "hit_tolerance", allow_zero=True)
        with self._lock:
            key = (tol, int(depth))
            pg = self._pyramids.get(key)
            if pg is None:
                g = self.grid
                pg = build_precomputation_grids(
                    self.near_obstacle(tol), g.occupied_mask, g.free_mask, tol, depth
                )
                self.n_computed["precomputation"] += 1
                self._pyramids[key] = pg
        return pg

    def derived(self, name: str, compute: Callable[[OccupancyGrid], T]) -> T:
        """A value the layers above compute from the map (e.g. its rotational symmetries),
        computed once by ``compute(grid)`` under ``name`` and kept with the fields."""
        with self._lock:
            if name not in self._derived:
                self._derived[name] = compute(self.grid)
                self.n_computed[name] += 1
            return cast(T, self._derived[name])

    def clear(self) -> None:
        """Forget every computed field (the counts stay)."""
        with self._lock:
            self._derived.clear()
            self._pyramids.clear()
            self._distance.clear()
            self._surface.clear()
            self._grown.clear()
            self._obstacle = None
            self._obstacle_k = None
            self._obstacle_m = None
            self._blocked = None


#: Largest squared distance [cells^2] :meth:`MapFields.obstacle_squared_cells` holds (uint16).
OBSTACLE_K_MAX = 65535
#: Largest distance [cells] below which OpenCV's float32 distance gives back the squared
#: distance exactly (its rounding error, about k 2^-23 for k = dx^2 + dy^2, stays below 1/2).
_EXACT_CELLS = 2000.0
#: Cells converted at a time from OpenCV's float32 to the float64 field (bounds temporaries).
_BLOCK_CELLS = 1 << 20


def distance_transform_edt(*args: Any, **kwargs: Any) -> Any:
    """:func:`scipy.ndimage.distance_transform_edt`, imported on first use: scipy.ndimage is
    not needed by a process that only tracks (its fields come from OpenCV)."""
    from scipy.ndimage import distance_transform_edt as edt

    return edt(*args, **kwargs)


def _obstacle_distance(occupied: NDArray[np.bool_], resolution: float) -> NDArray[np.float64]:
    """Distance [m] ``(H, W)`` float64 of each cell centre to the nearest ``occupied`` cell.

    Equal, value for value, to ``distance_transform_edt(~occupied) * resolution``: OpenCV's
    exact transform (``DIST_MASK_PRECISE``, float32) gives each cell's distance in cells, whose
    square rounds back to the integer ``k = dx^2 + dy^2`` below :data:`_EXACT_CELLS`; the
    field is ``sqrt(k) * resolution`` in float64, as scipy computes it. Peak memory about 13
    bytes per cell (scipy's transform needs about 40: its int32 feature transform, the index
    grids and a float64 copy per axis); a map with a cell farther than :data:`_EXACT_CELLS`
    from every obstacle, or with none, goes through scipy.
    """
    occ = np.asarray(occupied, dtype=bool)
    if not occ.any():
        return np.asarray(distance_transform_edt(~occ), dtype=np.float64) * resolution
    src = np.empty(occ.shape, dtype=np.uint8)
    np.logical_not(occ, out=src.view(np.bool_))  # 0 on the obstacles, 1 elsewhere
    cells = cv2.distanceTransform(src, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
    del src
    if float(cells.max()) >= _EXACT_CELLS:
        del cells
        return np.asarray(distance_transform_edt(~occ), dtype=np.float64) * resolution
    out = np.empty(occ.shape, dtype=np.float64)
    flat_in, flat_out = cells.reshape(-1), out.reshape(-1)
    for a in range(0, flat_in.size, _BLOCK_CELLS):
        blk = flat_out[a : a + _BLOCK_CELLS]
        np.multiply(flat_in[a : a + _BLOCK_CELLS], flat_in[a : a + _BLOCK_CELLS], out=blk)
        np.rint(blk, out=blk)  # k, exactly
        np.sqrt(blk, out=blk)
        np.multiply(blk, resolution, out=blk)
    return out


def _obstacle_squared_cells(occupied: NDArray[np.bool_]) -> NDArray[np.uint16]:
    """``(H, W)`` uint16: ``dx^2 + dy^2`` [cells^2] of each cell to the nearest ``occupied``
    cell, clipped at :data:`OBSTACLE_K_MAX` (all of it without an occupied cell).

    OpenCV's exact transform in float32, squared and rounded back to the integer (exact below
    :data:`_EXACT_CELLS` cells, far above the clip), a block at a time: peak about 7 bytes
    per cell."""
    occ = np.asarray(occupied, dtype=bool)
    out = np.full(occ.shape, OBSTACLE_K_MAX, dtype=np.uint16)
    if not occ.any():
        return out
    src = np.empty(occ.shape, dtype=np.uint8)
    np.logical_not(occ, out=src.view(np.bool_))  # 0 on the obstacles, 1 elsewhere
    cells = cv2.distanceTransform(src, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
    del src
    flat_in, flat_out = cells.reshape(-1), out.reshape(-1)
    for a in range(0, flat_in.size, _BLOCK_CELLS):
        blk = flat_in[a : a + _BLOCK_CELLS].astype(np.float64)
        np.multiply(blk, blk, out=blk)
        np.rint(blk, out=blk)
        np.minimum(blk, OBSTACLE_K_MAX, out=blk)
        flat_out[a : a + _BLOCK_CELLS] = blk
    return out


def distance_field(grid: OccupancyGrid | MapFields, max_dist: float = 2.0) -> DistanceField:
    """The shared distance field of ``grid`` clipped at ``max_dist`` [m]:
    ``MapFields.of(grid).distance(max_dist)``."""
    return MapFields.of(grid).distance(max_dist)


def surface_distance_field(grid: OccupancyGrid | MapFields, max_dist: float = 1.0) -> DistanceField:
    """The shared distance [m] to the map's obstacle surfaces:
    ``MapFields.of(grid).surface(max_dist)``."""
    return MapFields.of(grid).surface(max_dist)


def clear_distance_field_cache(grid: OccupancyGrid | MapFields) -> None:
    """Forget the fields computed for ``grid`` (:meth:`MapFields.clear`)."""
    MapFields.of(grid).clear()
