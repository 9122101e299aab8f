"""The compiled loops give bit for bit what the vectorised NumPy definitions give."""

from __future__ import annotations

import numpy as np
import pytest

from symloc.grid import OccupancyGrid
from symloc.grid.distance_field import distance_field
from symloc.mcl import kernels
from symloc.mcl.likelihood_field import (
    endpoint_flat_indices,
    endpoint_table_sums,
    laser_poses_grid,
)


def _field(rng: np.random.Generator) -> tuple[OccupancyGrid, object]:
    data = np.where(rng.random((37, 53)) < 0.1, 100, 0).astype(np.int8)
    data[rng.random(data.shape) < 0.05] = -1
    grid = OccupancyGrid(data, 0.05, origin=(-0.4, 0.3, 0.2))
    return grid, distance_field(grid, 0.5)


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("kind", ["pz3", "logpz"])
def test_endpoint_table_sums_bit_identical(seed: int, kind: str) -> None:
    rng = np.random.default_rng(seed)
    _, field = _field(rng)
    n, b = 700, 61
    # particles on and around the map (some beams end off the map, on the border)
    parts = np.column_stack(
        [rng.uniform(-2, 4, n), rng.uniform(-1, 3.5, n), rng.uniform(-np.pi, np.pi, n)]
    )
    ranges = rng.uniform(0.05, 3.0, b)
    angles = np.linspace(-np.pi, np.pi, b, endpoint=False)
    poses = laser_poses_grid(field, parts, np.array([0.1, -0.02, 0.05]))
    table = field.table(kind, 0.9, 0.1, 0.2, 3.5)
    want = table[endpoint_flat_indices(field, poses.copy(), ranges, angles)].sum(
        axis=1, dtype=np.float64
    )
    got = endpoint_table_sums(field, poses, ranges, angles, table)
    np.testing.assert_array_equal(got, want)


def test_split_over_threads_covers_every_index_once() -> None:
    seen = np.zeros(1001, dtype=np.int64)

    def run(a: int, b: int) -> None:
        seen[a:b] += 1

    kernels.split_over_threads(1001, 10**9, run)
    assert np.all(seen == 1)
    seen[:] = 0
    kernels.split_over_threads(1001, 10, run)  # small: one block in this thread
    assert np.all(seen == 1)


def test_parallel_sum_equals_serial(monkeypatch: pytest.MonkeyPatch) -> None:
    rng = np.random.default_rng(5)
    _, field = _field(rng)
    n = 5000
    parts = np.column_stack(
        [rng.uniform(0, 2.5, n), rng.uniform(0, 1.8, n), rng.uniform(-np.pi, np.pi, n)]
    )
    poses = laser_poses_grid(field, parts, np.zeros(3))
    r, a = rng.uniform(0.1, 2, 60), np.linspace(-1.5, 1.5, 60)
    table = field.table("pz3", 0.9, 0.1, 0.2, 3.5)
    par = endpoint_table_sums(field, poses, r, a, table)
    monkeypatch.setattr(kernels, "n_threads", lambda: 1)
    ser = endpoint_table_sums(field, poses, r, a, table)
    np.testing.assert_array_equal(par, ser)


def test_huge_table_path_equals_kernel(monkeypatch: pytest.MonkeyPatch) -> None:
    import symloc.mcl.likelihood_field as lf

    rng = np.random.default_rng(9)
    _, field = _field(rng)
    n = 300
    parts = np.column_stack(
        [rng.uniform(-1, 3.5, n), rng.uniform(-1, 2.5, n), rng.uniform(-np.pi, np.pi, n)]
    )
    poses = laser_poses_grid(field, parts, np.zeros(3))
    r, a = rng.uniform(0.1, 2, 45), np.linspace(-1.5, 1.5, 45)
    table = field.table("logpz", 0.9, 0.1, 0.2, 3.5)
    fast = endpoint_table_sums(field, poses, r, a, table)
    monkeypatch.setattr(lf, "_INT32_CELLS", 10)
    slow = endpoint_table_sums(field, poses, r, a, table)
    np.testing.assert_array_equal(fast, slow)


@pytest.mark.parametrize("model", ["diff", "diff-corrected"])
@pytest.mark.parametrize("seed", [0, 1])
def test_compiled_motion_model_bit_identical(model: str, seed: int) -> None:
    from symloc.mcl.motion_model import sample_motion_model_odometry

    rng = np.random.default_rng(seed)
    n = 2000
    parts = np.column_stack(
        [rng.uniform(-5, 5, n), rng.uniform(-5, 5, n), rng.uniform(-np.pi, np.pi, n)]
    )
    parts[:5, 2] = [np.pi, -np.pi, 3.14159, -3.14159, 0.0]
    a, b = np.array([0.3, -0.2, 3.0]), np.array([0.5, 0.1, -3.1])
    alphas = (0.2, 0.1, 0.3, 0.05, 0.0)
    fast = sample_motion_model_odometry(parts, a, b, alphas, np.random.default_rng(7), model=model)
    # a strided view takes the NumPy path
    wide = np.zeros((n, 6))
    wide[:, ::2] = parts
    slow = sample_motion_model_odometry(
        wide[:, ::2], a, b, alphas, np.random.default_rng(7), model=model
    )
    np.testing.assert_array_equal(fast, slow)


@pytest.mark.parametrize("seed", [0, 1])
def test_match_scores_kernel_equals_numpy(seed: int) -> None:
    from symloc.mcl import rival_search

    rng = np.random.default_rng(seed)
    _, field = _field(rng)
    poses = np.column_stack(
        [rng.uniform(-1, 3.5, 3000), rng.uniform(-1, 2.5, 3000), rng.uniform(-4, 4, 3000)]
    )
    pts = rng.uniform(-2, 2, (37, 2))
    tol = rng.uniform(0.0, 0.4, 37)
    fast = rival_search.match_scores(field, poses, pts, tol)
    # the former vectorised definition
    r = np.hypot(pts[:, 0], pts[:, 1])
    a = np.arctan2(pts[:, 1], pts[:, 0])
    idx = endpoint_flat_indices(field, field.grid_frame_poses(poses), r, a)
    slow = np.count_nonzero(field.padded.ravel()[idx] <= tol.astype(np.float32), axis=1) / 37
    np.testing.assert_array_equal(fast, slow)
