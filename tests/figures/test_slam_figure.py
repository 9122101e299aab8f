"""The SLAM map figure draws a large map from a block-averaged image, not the full grid."""

from __future__ import annotations

import numpy as np
import pytest

import symloc.figures.slam as fig_slam
from symloc.grid.occupancy_grid import OccupancyGrid


def test_a_large_map_is_drawn_from_block_means(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(fig_slam, "_MAX_IMAGE_SIDE", 100)
    monkeypatch.setattr(fig_slam, "_BAND_ROWS", 64)
    rng = np.random.default_rng(0)
    data = rng.integers(-1, 101, size=(1003, 777)).astype(np.int8)
    img = fig_slam._grid_image(OccupancyGrid(data, 0.05))
    gray = np.where(data < 0, 0.5, 1.0 - data / 100.0)
    f = 11  # the smallest factor that brings 1003 rows under 100
    expected = np.array(
        [[gray[i : i + f, j : j + f].mean() for j in range(0, 777, f)] for i in range(0, 1003, f)]
    )
    assert img.shape == expected.shape == (92, 71)
    assert np.allclose(img, expected, rtol=0, atol=1e-12)


def test_a_small_map_is_drawn_cell_for_cell() -> None:
    data = np.array([[-1, 0], [100, 50]], dtype=np.int8)
    img = fig_slam._grid_image(OccupancyGrid(data, 0.05))
    assert np.array_equal(img, [[0.5, 1.0], [0.0, 0.5]])
    assert np.array_equal(fig_slam._known_box(data), [[0, 0], [1, 1]])
    assert fig_slam._known_box(np.full((2, 2), -1, np.int8)) is None
