"""Ground-truth occupancy grids from worlds."""

from __future__ import annotations

import math

import numpy as np
import pytest

from symloc.errors import ConfigurationError
from symloc.grid import FREE, OCCUPIED, UNKNOWN
from symloc.sim.rasterize import world_to_grid
from symloc.sim.rooms import build_room


def _value(grid, x: float, y: float) -> int:
    rc = grid.world_to_cell([[x, y]])[0]
    return int(grid.data[rc[0], rc[1]])


def test_paper_room_grid_shows_boards_and_free_inside() -> None:
    room = build_room("square", 1.5 * math.sqrt(2))
    grid = world_to_grid(room.world, 0.05)
    assert _value(grid, 0.0, 0.0) == FREE
    assert _value(grid, 1.5, 0.3) == OCCUPIED  # the board at x = 1.5
    assert _value(grid, 2.5, 0.0) == FREE  # lab floor (enclosed by the lab walls)
    assert _value(grid, -4.0, 0.0) == OCCUPIED  # lab wall
    assert grid.data[0, 0] == UNKNOWN


def test_walls_below_min_height_are_not_drawn() -> None:
    room = build_room("square", 1.5 * math.sqrt(2))
    grid = world_to_grid(room.world, 0.05, min_height=0.5)
    assert _value(grid, 1.5, 0.3) == FREE


def test_open_room_needs_seed() -> None:
    room = build_room("square", 2.0, lab=False, door=True)
    grid = world_to_grid(room.world, 0.05)
    assert _value(grid, 0.0, 0.0) == UNKNOWN
    seeded = world_to_grid(room.world, 0.05, free_seeds=[[0.0, 0.0]])
    assert _value(seeded, 0.0, 0.0) == FREE
    assert np.count_nonzero(seeded.occupied_mask) == np.count_nonzero(grid.occupied_mask)


def test_grid_resolution_and_error() -> None:
    room = build_room("circle", 2.0, lab=False)
    grid = world_to_grid(room.world, 0.1, margin=0.5)
    assert grid.resolution == 0.1
    x0, x1, y0, y1 = grid.extent()
    assert x0 < -2.5
    assert x1 > 2.5
    assert y0 < -2.5
    assert y1 > 2.5
    assert _value(grid, 0.0, 0.0) == FREE
    assert _value(grid, 2.0, 0.0) == OCCUPIED
    with pytest.raises(ConfigurationError, match="resolution"):
        world_to_grid(room.world, 0.0)


def test_noise_free_scan_points_fall_on_occupied_cells() -> None:
    from symloc.geometry import transform_points
    from symloc.sim.lidar import RPLIDAR_A2, simulate_scan

    room = build_room("pentagon", 3.0, furniture=2, tables=1, door=True)
    grid = world_to_grid(room.world, 0.05, free_seeds=[room.center])
    pose = np.array([0.3, -0.2, 0.4])
    scan = simulate_scan(room.world, pose, RPLIDAR_A2, noise=False)
    pts = transform_points(pose, scan.to_points().points)
    # a point on a wall is within one cell of an occupied cell
    cells = grid.world_to_cell(pts)
    near = np.zeros(len(cells), dtype=bool)
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            rc = cells + np.array([dr, dc])
            near |= grid.data[rc[:, 0], rc[:, 1]] == OCCUPIED
    assert near.all()
    assert _value(grid, *pose[:2]) == FREE
