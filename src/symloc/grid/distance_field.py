"""Distance field and likelihood-field lookups on an occupancy grid.

The likelihood-field sensor model (Thrun, Burgard and Fox, *Probabilistic Robotics*, 2005,
Table 6.3; ROS amcl's ``map_update_cspace``) needs, for every cell, the distance [m] to the
nearest occupied cell, clipped at ``laser_likelihood_max_dist``. This module computes it;
:class:`symloc.grid.fields.MapFields` computes it once per map and shares it. OpenCV's exact Euclidean distance transform (``cv2.distanceTransform`` with
``DIST_MASK_PRECISE``, Felzenszwalb and Huttenlocher's algorithm) gives the squared distance in
cells, and a small table maps each squared distance to metres exactly as
:func:`scipy.ndimage.distance_transform_edt` with ``sampling`` computes them. A 30-million-cell
map takes about a second and 5 bytes per cell at the peak (the transform is turned into
metres in place); the field keeps 4.

Lookups go through a *padded* float32 table: the grid plus a one-cell border that holds the
clipped maximum, so any world point is one clip and one fancy index away from its value, and a
point off the map reads the maximum distance exactly as nav2_amcl does (``!MAP_VALID`` ->
``max_occ_dist``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from symloc._checks import check_positive
from symloc.errors import ConfigurationError
from symloc.geometry import compose, inverse
from symloc.grid.occupancy_grid import OccupancyGrid

__all__ = [
    "DistanceField",
    "compute_distance_field",
    "compute_surface_distance_field",
]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class DistanceField:
    """Distance [m] from each cell to the nearest occupied cell, clipped at ``max_dist``.

    Get it from :meth:`symloc.grid.fields.MapFields.distance` (computed once per map and
    ``max_dist``).

    Attributes
    ----------
    grid : OccupancyGrid
        The map it was computed from.
    max_dist : float
        Clip distance [m] (nav2's ``laser_likelihood_max_dist``).
    padded : ndarray of shape (H + 2, W + 2), float32
        Clipped distance [m] of each cell centre to the nearest occupied cell centre, with a
        one-cell border of ``max_dist`` (off-map value).
    """

    grid: OccupancyGrid
    max_dist: float
    padded: NDArray[np.float32] = field(repr=False)
    _tables: dict[tuple[str, float, float, float, float], NDArray[np.float32]] = field(
        default_factory=dict, repr=False
    )

    @property
    def distances(self) -> NDArray[np.float32]:
        """Clipped distances ``(H, W)`` [m], float32: a read-only view of :attr:`padded`."""
        return self.padded[1:-1, 1:-1]

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

            def per_cell(d32: NDArray[np.float32]) -> NDArray[np.float32]:
                d = d32.astype(np.float64)
                pz = z_hit * np.exp(-(d * d) / (2.0 * sigma_hit * sigma_hit)) + z_rand / range_max
                if kind == "pz3":
                    pz = pz**3
                elif kind == "logpz":
                    with np.errstate(divide="ignore"):
                        pz = np.log(pz)
                return pz.astype(np.float32)

            src = self.padded.ravel()
            out = _per_level(src, self.grid.resolution, self.max_dist, per_cell)
            if out is None:  # distances not of the transform's levels: cell by cell
                out = np.empty(src.size, dtype=np.float32)
                for a in range(0, src.size, _TABLE_BLOCK):  # float64 temporaries of one block
                    out[a : a + _TABLE_BLOCK] = per_cell(src[a : a + _TABLE_BLOCK])
            tab = out
            tab.setflags(write=False)
            if len(self._tables) > 16:
                self._tables.clear()
            self._tables[key] = tab
        return tab


#: Cells per block when a per-cell table is computed (bounds the float64 temporaries).
_TABLE_BLOCK = 1 << 20


def _per_level(
    src: NDArray[np.float32],
    resolution: float,
    max_dist: float,
    fn: Callable[[NDArray[np.float32]], NDArray[np.float32]],
) -> NDArray[np.float32] | None:
    """``fn`` of every value of ``src`` (a field's padded distances, flat), computed once per
    distinct distance: a field holds only the transform's levels (the clipped metres of a
    squared distance of ``k`` cells, :func:`_metres_by_squared_cells`), a few hundred, so
    ``fn`` runs on those and each cell takes its level's value: the same float32 values as
    ``fn(src)`` cell by cell, for about a fifth of the CPU on a map (a table of ``exp`` and
    ``log`` over millions of cells costs tens of milliseconds). None when some value is not
    a level (each cell's own level is checked)."""
    k_cap = int(np.ceil(max_dist / resolution)) ** 2 + 2
    levels = _metres_by_squared_cells(k_cap, resolution, max_dist)
    top = np.float32(max_dist)
    inv = np.float32(1.0 / resolution)
    values = fn(levels)
    out = np.empty(src.size, dtype=np.float32)
    for a in range(0, src.size, _LEVEL_BLOCK):
        d = src[a : a + _LEVEL_BLOCK]
        k = d * inv
        np.multiply(k, k, out=k)
        np.rint(k, out=k)
        np.minimum(k, np.float32(k_cap), out=k)
        ki = k.astype(np.intp)
        ki[d >= top] = k_cap  # the clip's cells (the border among them)
        # indices within 0..k_cap by construction: "clip" skips take's bounds checks
        if not np.array_equal(np.take(levels, ki, mode="clip"), d):
            return None
        np.take(values, ki, mode="clip", out=out[a : a + _LEVEL_BLOCK])
    return out


#: Cells per block of :func:`_per_level` (its temporaries stay in the cache and are reused).
_LEVEL_BLOCK = 1 << 17


def _metres_by_squared_cells(k_max: int, resolution: float, max_dist: float) -> NDArray[np.float32]:
    """``(k_max + 1,)``: the clipped distance [m] of a squared distance of ``k`` cells.

    For each ``k = dx^2 + dy^2`` the metres are computed as
    :func:`scipy.ndimage.distance_transform_edt` computes them with ``sampling``,
    ``sqrt((dx res)^2 + (dy res)^2)`` in float64, then clipped and rounded to float32; a ``k``
    that is no sum of two squares never occurs and gets ``sqrt(k) res``.
    """
    k = np.arange(k_max + 1)
    out = np.sqrt(k.astype(np.float64)) * resolution
    r = int(np.sqrt(k_max)) + 1
    dx, dy = np.meshgrid(np.arange(r + 1), np.arange(r + 1), indexing="ij")
    kk = (dx * dx + dy * dy).ravel()
    ok = kk <= k_max
    ax = dx.ravel()[ok] * resolution
    ay = dy.ravel()[ok] * resolution
    out[kk[ok]] = np.sqrt(ax * ax + ay * ay)
    return np.minimum(out, max_dist).astype(np.float32)


def _padded_distances(
    target: NDArray[np.bool_], resolution: float, max_dist: float
) -> NDArray[np.float32]:
    """Clipped distance [m] to the nearest ``True`` cell of ``target (H, W)``, padded.

    Returns ``(H + 2, W + 2)`` float32 with a one-cell border of ``max_dist``; without any
    ``True`` cell every value is ``max_dist``.
    """
    h, w = target.shape
    if not target.any():
        return np.full((h + 2, w + 2), max_dist, dtype=np.float32)
    # the transform runs on the padded frame (the border holds no target, so every map cell
    # keeps its distance) and is turned into metres in place: one float32 array of the map's
    # size at the peak, not two
    src = np.ones((h + 2, w + 2), dtype=np.uint8)
    np.logical_not(target, out=src[1:-1, 1:-1].view(np.bool_))  # 0 on the targets
    padded = np.asarray(
        cv2.distanceTransform(src, cv2.DIST_L2, cv2.DIST_MASK_PRECISE), dtype=np.float32
    )  # float32, exact (no copy)
    del src
    # squared distance in cells, exact: it holds the float32 root of an integer below 2^24
    k_cap = int(np.ceil(max_dist / resolution)) ** 2 + 2
    lut = _metres_by_squared_cells(k_cap, resolution, max_dist)
    cap = np.float32(np.sqrt(k_cap))
    rows = max(1, _LEVEL_BLOCK // max(1, w))  # small blocks: temporaries in the cache
    for a in range(1, h + 1, rows):
        blk = padded[a : min(a + rows, h + 1), 1:-1]
        np.minimum(blk, cap, out=blk)
        np.multiply(blk, blk, out=blk)
        np.rint(blk, out=blk)
        # indices within 0..k_cap (the minimum above): "clip" skips take's bounds checks
        blk[...] = np.take(lut, blk.astype(np.intp), mode="clip")
    padded[[0, -1], :] = max_dist
    padded[:, [0, -1]] = max_dist
    return padded


def grown_padded_distances(
    own: NDArray[np.float32],
    target: NDArray[np.bool_],
    pad: int,
    resolution: float,
    max_dist: float,
) -> NDArray[np.float32]:
    """:func:`_padded_distances` of ``target (H, W)`` grown by ``pad`` cells of no target on
    every side, from the map's own ``own = _padded_distances(target, resolution, max_dist)``.

    Returns ``(H + 2 pad + 2, W + 2 pad + 2)`` float32, value for value what the transform of
    the grown mask gives, with ``pad`` at least ``ceil(max_dist / resolution) + 1``: inside
    the map the nearest target is the same (the margin holds none), so the map's values are
    copied; a margin cell within ``max_dist`` of a target has it within ``pad`` cells of its
    own edge of the map, so four strips ``2 pad`` cells wide along the edges (margin and map)
    give its distance exactly, and every farther one reads ``max_dist`` either way. About a
    sixth of the cells of one transform of the grown map.
    """
    h, w = target.shape
    if pad < math.ceil(max_dist / resolution) + 1:
        raise ConfigurationError(
            f"pad: expected at least ceil(max_dist / resolution) + 1 cells, got {pad}"
        )
    hg, wg = h + 2 * pad, w + 2 * pad
    # the map's values copied, the margins (and the border) set to max_dist: every cell
    # written once (a full fill first would write the map's part twice)
    out = np.empty((hg + 2, wg + 2), dtype=np.float32)
    r0, r1, c0, c1 = 1 + pad, 1 + pad + h, 1 + pad, 1 + pad + w
    out[:r0, :] = max_dist
    out[r1:, :] = max_dist
    out[r0:r1, :c0] = max_dist
    out[r0:r1, c1:] = max_dist
    out[r0:r1, c0:c1] = own[1:-1, 1:-1]
    band = 2 * pad  # strip width in the grown frame: the margin and as much of the map

    def strip(r0: int, r1: int, c0: int, c1: int) -> NDArray[np.float32]:
        """Distances of the grown frame's rows r0:r1, columns c0:c1 from their targets."""
        sub = np.zeros((r1 - r0, c1 - c0), dtype=np.bool_)
        mr0, mr1 = max(r0, pad), min(r1, pad + h)  # the map's part of the strip
        mc0, mc1 = max(c0, pad), min(c1, pad + w)
        if mr0 < mr1 and mc0 < mc1:
            sub[mr0 - r0 : mr1 - r0, mc0 - c0 : mc1 - c0] = target[
                mr0 - pad : mr1 - pad, mc0 - pad : mc1 - pad
            ]
        return _padded_distances(sub, resolution, max_dist)[1:-1, 1:-1]

    top = strip(0, min(band, hg), 0, wg)
    out[1 : 1 + pad, 1:-1] = top[:pad]
    bottom = strip(max(0, hg - band), hg, 0, wg)
    out[1 + hg - pad : 1 + hg, 1:-1] = bottom[bottom.shape[0] - pad :]
    left = strip(0, hg, 0, min(band, wg))
    out[1 : 1 + hg, 1 : 1 + pad] = left[:, :pad]
    right = strip(0, hg, max(0, wg - band), wg)
    out[1 : 1 + hg, 1 + wg - pad : 1 + wg] = right[:, right.shape[1] - pad :]
    return out


def compute_distance_field(grid: OccupancyGrid, max_dist: float) -> DistanceField:
    """The distance field of ``grid`` clipped at ``max_dist`` [m], computed now (no cache).

    Callers want :meth:`symloc.grid.fields.MapFields.distance`, which computes it once per map.
    """
    padded = _padded_distances(grid.occupied_mask, grid.resolution, max_dist)
    padded.setflags(write=False)
    return DistanceField(grid, max_dist, padded)


def compute_surface_distance_field(grid: OccupancyGrid, max_dist: float) -> DistanceField:
    """The distance [m] to the map's obstacle surfaces, computed now (no cache).

    Callers want :meth:`symloc.grid.fields.MapFields.surface` (see there for the definition).
    """
    occ = grid.occupied_mask
    free = grid.free_mask
    # the occupied cells that face free space (within two cells of it, 4-connected steps): a
    # wall's band of hits seen from the room, or the skin of a filled obstacle
    if free.any():
        near = cv2.dilate(free.view(np.uint8), _CROSS, iterations=2)
        shell = occ & near.view(np.bool_)
        del near
    else:
        shell = occ
    centre: NDArray[np.bool_] = shell
    if shell.any():
        centre = _skeleton(shell)
    padded = _padded_distances(centre, grid.resolution, max_dist)
    padded.setflags(write=False)
    return DistanceField(grid, max_dist, padded)


#: The 4-neighbourhood (scipy.ndimage's default structure for binary dilation).
_CROSS = np.array([[0, 1, 0], [1, 1, 1], [0, 1, 0]], dtype=np.uint8)


def _skeleton(mask: NDArray[np.bool_]) -> NDArray[np.bool_]:
    """:func:`skimage.morphology.skeletonize` of ``mask``, run only on its bounding box.

    scikit-image is imported here, on the first surface field, not with the module: it takes
    a third of a second to import, and a process that only tracks (the filter, the
    confidence verdict) never computes a surface field.
    """
    from skimage.morphology import skeletonize  # lazy: a heavy import few processes need

    rows = np.flatnonzero(mask.any(axis=1))
    cols = np.flatnonzero(mask.any(axis=0))
    r0, r1 = max(0, int(rows[0]) - 1), min(mask.shape[0], int(rows[-1]) + 2)
    c0, c1 = max(0, int(cols[0]) - 1), min(mask.shape[1], int(cols[-1]) + 2)
    out = np.zeros(mask.shape, dtype=np.bool_)
    out[r0:r1, c0:c1] = skeletonize(mask[r0:r1, c0:c1])  # type: ignore[no-untyped-call]
    return out
