"""Rotational self-symmetry of an occupancy grid (is the *map* itself symmetric?).

A pose that AMCL converged to cannot be earned when the map maps onto itself under a rotation
that also carries the pose onto a copy explaining the scan as well: in a 40 m hallway whose far
ends the lidar sees one at a time, the two ends look alike and AMCL's particles die out at one
of them by chance. :func:`map_symmetries` finds such rotations once per map: the occupied cells
are rotated by ``2 pi / k`` about a centre (their centroid, refined by a local search: a box or
a door pulls the centroid off the rotation centre) and the share of rotated cells landing
within ``tolerance`` of an occupied cell is measured; orders whose share reaches
``min_overlap`` are symmetries of the map. The default (0.6) keeps *near* symmetries too (a
rectangle with one box, uneven chamfers): whether the scan tells their copies apart is the
localizer's decision, made with the scan.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from symloc._checks import check_in_range, check_positive
from symloc.grid import OccupancyGrid
from symloc.grid.fields import MapFields

__all__ = ["MapSymmetry", "map_symmetries"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class MapSymmetry:
    """The map maps onto itself when rotated by ``2 pi / order`` about ``centre`` (2,) [m];
    ``overlap`` is the share of occupied cells that land on occupied cells."""

    centre: FloatArray
    order: int
    overlap: float


def map_symmetries(
    grid: OccupancyGrid | MapFields,
    orders: tuple[int, ...] = (2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12),
    *,
    tolerance: float = 0.1,
    min_overlap: float = 0.6,
) -> list[MapSymmetry]:
    """The rotational symmetries of ``grid`` about its occupied cells' centroid.

    Parameters
    ----------
    grid : OccupancyGrid or MapFields
        The map, or its shared fields (the distance to the nearest occupied cell is read from
        :meth:`~symloc.grid.fields.MapFields.obstacle_distance`).
    orders : tuple of int
        Orders k (>= 2) to test (rotation by ``2 pi / k``).
    tolerance : float
        A rotated occupied cell matches when it lies within this distance [m] of an occupied cell.
    min_overlap : float
        Share in (0, 1] of occupied cells that must match.

    Returns
    -------
    list of MapSymmetry
        Every tested order that passes, highest first (empty for an asymmetric map).
    """
    check_positive(tolerance, "tolerance")
    check_in_range(min_overlap, "min_overlap", 1e-9, 1.0)
    fields = MapFields.of(grid)
    grid = fields.grid
    occ = np.asarray(grid.occupied_mask, dtype=bool)
    rc = np.argwhere(occ)
    if rc.shape[0] < 10:
        return []
    pts = np.asarray(grid.cell_to_world(rc), dtype=np.float64)[:, :2]
    dist = fields.obstacle_distance()

    def overlap(centre: FloatArray, k: int) -> float:
        a = 2.0 * math.pi / k
        c, s = math.cos(a), math.sin(a)
        d = pts - centre
        rot = centre + np.column_stack([c * d[:, 0] - s * d[:, 1], s * d[:, 0] + c * d[:, 1]])
        cells = np.asarray(grid.world_to_cell(rot))
        inside = np.asarray(grid.in_bounds(cells), dtype=bool)
        hit = np.zeros(len(rot), dtype=bool)
        ci = cells[inside].astype(int)
        hit[inside] = dist[ci[:, 0], ci[:, 1]] <= tolerance
        return float(hit.mean())

    centroid = pts.mean(axis=0)
    out: list[MapSymmetry] = []
    for k in sorted({int(k) for k in orders if int(k) >= 2}, reverse=True):
        # a feature that breaks the symmetry (a box, a door, an uneven chamfer) pulls the
        # centroid off the rotation centre: refine it by a coarse-to-fine local search
        centre, best = centroid.copy(), overlap(centroid, k)
        for step in (4.0 * tolerance, 2.0 * tolerance, tolerance, 0.5 * tolerance):
            improved = True
            while improved:
                improved = False
                for dx, dy in ((step, 0.0), (-step, 0.0), (0.0, step), (0.0, -step)):
                    cand = centre + np.array([dx, dy])
                    share = overlap(cand, k)
                    if share > best + 1e-9:
                        centre, best, improved = cand, share, True
        if best >= min_overlap:
            out.append(MapSymmetry(centre=centre, order=k, overlap=best))
    return out
