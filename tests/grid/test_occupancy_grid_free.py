"""OccupancyGrid.is_free: free_mask's test on some of the grid's values."""

from __future__ import annotations

import numpy as np

from symloc.grid import OccupancyGrid


def test_is_free_matches_free_mask_on_any_block() -> None:
    data = np.array([[-1, 0, 10], [24, 25, 26], [64, 65, 100]], dtype=np.int8)
    g = OccupancyGrid(data, 0.05, (0.0, 0.0, 0.0), 0.65, 0.25)
    assert np.array_equal(g.is_free(g.data), g.free_mask)
    assert g.free_mask.tolist() == [[False, True, True], [True, False, False], [False] * 3]
    assert np.array_equal(g.is_free(g.data[::2, ::2]), g.free_mask[::2, ::2])
    assert bool(g.is_free(g.data[0, 1]))
    assert not bool(g.is_free(g.data[1, 1]))
