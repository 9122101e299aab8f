"""The replay figure's map image (symloc.figures.replay)."""

from __future__ import annotations

import numpy as np

from symloc.figures.replay import _map_image


def test_map_image_grey_levels_and_blocks_that_keep_thin_walls() -> None:
    d = np.array([[-1, 0, 100], [50, 0, 0]], np.int8)
    # a small map: one grey level per cell (free 1, occupied 0, unknown 0.75)
    np.testing.assert_allclose(_map_image(d), np.where(d < 0, 0.75, 1.0 - d / 100.0))
    big = np.zeros((2500, 1300), np.int8)
    big[1001, :] = 100  # a wall one cell thick
    big[:, 7] = -1
    img = _map_image(big, max_side=1000)  # blocks of 3 x 3 cells
    assert img.shape == (834, 434)
    assert img.dtype == np.float32
    assert (img[1001 // 3] == 0.0).all()  # the wall stays drawn, as dark as it is
    assert (img[:, 7 // 3][img[:, 7 // 3] > 0] == 0.75).all()
