"""Small synthetic maps and scans for the mcl tests (no simulator needed)."""

from __future__ import annotations

import numpy as np

from symloc.grid import OccupancyGrid
from symloc.mcl.beam_model import raycast_grid
from symloc.scan import LaserScan

RES = 0.05


def asymmetric_room() -> OccupancyGrid:
    """An 8 m x 6 m room with two obstacles placed without symmetry."""
    d = np.zeros((120, 160), np.int8)
    d[0, :] = d[-1, :] = d[:, 0] = d[:, -1] = 100
    d[30:50, 40:60] = 100
    d[80:85, 100:140] = 100
    d[60:100, 20:24] = 100
    return OccupancyGrid(d, RES)


def twin_rooms() -> OccupancyGrid:
    """Two identical 2.7 m rooms side by side, each with the same bar inside, in unknown
    space: a pose in one has a rival in the other."""
    data = np.full((60, 130), -1, np.int8)
    for c0 in (5, 70):
        data[5:55, c0 : c0 + 55] = 0
        data[5, c0 : c0 + 55] = data[54, c0 : c0 + 55] = 100
        data[5:55, c0] = data[5:55, c0 + 54] = 100
        data[20:24, c0 + 10 : c0 + 30] = 100
    return OccupancyGrid(data, RES)


def synthetic_scan(
    grid: OccupancyGrid, pose: np.ndarray, rng: np.random.Generator, n: int = 180
) -> LaserScan:
    """A 360-degree scan ray cast on ``grid`` from ``pose`` with 1 cm range noise."""
    ang = -np.pi + 2 * np.pi / n * np.arange(n)
    r = raycast_grid(grid, np.repeat(np.asarray(pose)[None, :2], n, 0), ang + pose[2], 12.0)
    r = np.where(r >= 12.0, np.inf, r + rng.normal(0.0, 0.01, n))
    return LaserScan(-np.pi, 2 * np.pi / n, 0.05, 12.0, r)
