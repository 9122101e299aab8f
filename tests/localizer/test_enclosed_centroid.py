"""The claim gate's scale centre: the middle of the mapped room, not of everything seen free."""

from __future__ import annotations

import numpy as np
import pytest

from symloc.grid import OccupancyGrid
from symloc.localizer.build import enclosed_centroid

RES = 0.05


def _room_seen_through_glass(glass: bool) -> OccupancyGrid:
    """A 4 m square room (walls 0 -> 4 m) in a 12 m grid; with ``glass`` its east wall lets
    beams through, and the space beyond it is free out to 8 m east of the room."""
    n = int(12 / RES)
    data = np.full((n, n), -1, dtype=np.int8)
    lo, hi = int(4 / RES), int(8 / RES)  # the room's walls at 4 and 8 m of the grid
    data[lo : hi + 1, lo : hi + 1] = 0
    data[lo, lo : hi + 1] = 100
    data[hi, lo : hi + 1] = 100
    data[lo : hi + 1, lo] = 100
    data[lo : hi + 1, hi] = 100
    if glass:
        data[lo + 1 : hi, hi + 1 :] = 0  # seen through the glass: free, no wall beyond
    return OccupancyGrid(data, RES, np.array([-6.0, -6.0, 0.0]))


def test_free_space_seen_through_glass_does_not_move_the_centre() -> None:
    glass = _room_seen_through_glass(True)
    rows, cols = np.nonzero(glass.free_mask)
    all_free = glass.cell_to_world(np.column_stack([rows, cols]).astype(float)).mean(axis=0)
    assert all_free[0] > 0.5  # what the mean of every free cell gives: pulled east
    np.testing.assert_allclose(enclosed_centroid(glass), [0.0, 0.0], atol=RES)
    np.testing.assert_allclose(
        enclosed_centroid(glass), enclosed_centroid(_room_seen_through_glass(False)), atol=RES
    )


@pytest.mark.parametrize("walls", [0, 2])
def test_without_walls_enclosing_an_area_every_free_cell_counts(walls: int) -> None:
    data = np.full((40, 80), -1, dtype=np.int8)
    data[10:30, 40:80] = 0  # free cells east of the grid's middle only
    data[0, :walls] = 100  # none, or two cells on a line: no hull
    grid = OccupancyGrid(data, RES, np.zeros(3))
    np.testing.assert_allclose(enclosed_centroid(grid), [60 * RES, 20 * RES], atol=RES)


def test_a_grid_without_free_cells_gives_its_centre() -> None:
    grid = OccupancyGrid(np.full((20, 40), -1, dtype=np.int8), RES, np.array([1.0, 2.0, 0.0]))
    np.testing.assert_allclose(enclosed_centroid(grid), [1.0 + 20 * RES, 2.0 + 10 * RES], atol=RES)
