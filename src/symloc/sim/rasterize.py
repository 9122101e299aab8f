"""Ground-truth occupancy grid of what the lidar sees in a :class:`~symloc.sim.world.World`.

Walls and circles taller than the lidar's mount height are drawn as occupied cells (100); every
other cell that cannot be reached from the grid's border without crossing an occupied cell
(4-connectivity) is free (0): the inside of closed rooms and of the lab. Cells connected to the
border are unknown (-1), as they would be in a map the robot built from inside. If a room has a
door into an open world, its inside is connected to the border too; pass ``free_seeds`` to mark
the component(s) holding those points free instead.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike
from scipy import ndimage

from symloc._checks import check_positive
from symloc.grid import FREE, OCCUPIED, UNKNOWN, OccupancyGrid
from symloc.sim.lidar import LIDAR_MOUNT_HEIGHT
from symloc.sim.world import World

__all__ = ["world_to_grid"]


def world_to_grid(
    world: World,
    resolution: float = 0.05,
    *,
    min_height: float = LIDAR_MOUNT_HEIGHT,
    margin: float = 0.5,
    free_seeds: ArrayLike | None = None,
) -> OccupancyGrid:
    """Rasterise the lidar-visible walls of ``world`` into an :class:`OccupancyGrid`.

    Parameters
    ----------
    world : World
    resolution : float
        Cell size [m/cell].
    min_height : float
        Primitives no taller than this [m] are not drawn (the lidar does not see them).
    margin : float
        Unknown border [m] around the world's bounding box.
    free_seeds : array of shape (K, 2), optional
        World points [m] whose connected free space is marked free even if it reaches the
        border (e.g. the robot's start inside a room with an open door).

    Returns
    -------
    OccupancyGrid
        100 on walls, 0 in enclosed (or seeded) free space, -1 elsewhere; origin at the
        lower-left corner of the padded bounding box, yaw 0.
    """
    res = check_positive(resolution, "resolution")
    pad = check_positive(margin, "margin", allow_zero=True) + res
    visible = world.visible_above(min_height)
    xmin, xmax, ymin, ymax = world.bounds()
    x0, y0 = xmin - pad, ymin - pad
    width = math.ceil((xmax + pad - x0) / res)
    height = math.ceil((ymax + pad - y0) / res)
    grid0 = OccupancyGrid(np.zeros((1, 1), dtype=np.int8), res, np.array([x0, y0, 0.0]))
    occ = np.zeros((height, width), dtype=bool)
    step = res / 4.0
    pts = []
    for seg in visible.walls:
        n = max(2, math.ceil(math.hypot(seg[2] - seg[0], seg[3] - seg[1]) / step) + 1)
        t = np.linspace(0.0, 1.0, n)[:, None]
        pts.append(seg[:2] + t * (seg[2:] - seg[:2]))
    for cx, cy, r in visible.circles:
        n = max(8, math.ceil(2 * math.pi * r / step))
        a = np.linspace(0.0, 2 * math.pi, n, endpoint=False)
        pts.append(np.column_stack([cx + r * np.cos(a), cy + r * np.sin(a)]))
    if pts:
        cells = grid0.world_to_cell(np.concatenate(pts))
        ok = (
            (cells[:, 0] >= 0) & (cells[:, 0] < height) & (cells[:, 1] >= 0) & (cells[:, 1] < width)
        )
        occ[cells[ok, 0], cells[ok, 1]] = True
    labels, _ = ndimage.label(~occ)
    border = np.unique(np.concatenate([labels[0], labels[-1], labels[:, 0], labels[:, -1]]))
    outside = np.isin(labels, border[border > 0])
    if free_seeds is not None:
        seeds = grid0.world_to_cell(np.asarray(free_seeds, dtype=np.float64).reshape(-1, 2))
        ok = (
            (seeds[:, 0] >= 0) & (seeds[:, 0] < height) & (seeds[:, 1] >= 0) & (seeds[:, 1] < width)
        )
        seed_labels = labels[seeds[ok, 0], seeds[ok, 1]]
        outside &= ~np.isin(labels, seed_labels[seed_labels > 0])
    data = np.full((height, width), FREE, dtype=np.int8)
    data[outside] = UNKNOWN
    data[occ] = OCCUPIED
    return OccupancyGrid(data, res, np.array([x0, y0, 0.0]))
