"""The compiled loops give bit for bit what the vectorised NumPy definitions give."""

from __future__ import annotations

import numpy as np
import pytest
from mcl_fixtures import twin_rooms

from symloc.grid import OccupancyGrid
from symloc.grid.fields import distance_field
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


@pytest.mark.parametrize("at_least", [0.0, 0.3, 0.55, 0.9, 1.0])
def test_match_scores_early_exit_exact_above_threshold(at_least: float) -> None:
    from symloc.mcl import rival_search

    rng = np.random.default_rng(3)
    _, field = _field(rng)
    poses = np.column_stack(
        [rng.uniform(0, 2.5, 4000), rng.uniform(0, 1.8, 4000), rng.uniform(-4, 4, 4000)]
    )
    pts = rng.uniform(-1, 1, (41, 2))
    exact = rival_search.match_scores(field, poses, pts, 0.2)
    fast = rival_search.match_scores(field, poses, pts, 0.2, at_least=at_least)
    keep = exact >= at_least
    np.testing.assert_array_equal(fast >= at_least, keep)
    np.testing.assert_array_equal(fast[keep], exact[keep])


def test_find_rival_same_with_and_without_early_exit(monkeypatch: pytest.MonkeyPatch) -> None:
    from symloc.mcl import rival_search

    # two identical rooms side by side: a rival exists
    grid = twin_rooms()
    field = rival_search.padded_field(grid, 0.6)
    est = np.array([1.5, 1.5, 0.3])
    ang = np.linspace(-np.pi, np.pi, 90, endpoint=False)
    from symloc.mcl.beam_model import raycast_grid

    r = raycast_grid(grid, np.repeat(est[None, :2], 90, 0), ang + est[2], 8.0)
    pts = np.column_stack([r * np.cos(ang), r * np.sin(ang)])[r < 8.0]
    fast = rival_search.find_rival(field, pts, est, tol=0.1)
    real = kernels.count_within

    def exact(*a: object) -> None:
        b = list(a)
        b[10] = 0  # need: no early exit
        real(*b)

    monkeypatch.setattr(kernels, "count_within", exact)
    slow = rival_search.find_rival(field, pts, est, tol=0.1)
    assert fast.ambiguous == slow.ambiguous
    assert fast.estimate_score == slow.estimate_score
    assert fast.rival_score == slow.rival_score
    assert fast.n_candidates == slow.n_candidates
    np.testing.assert_array_equal(fast.rival_pose, slow.rival_pose)


def test_match_scores_with_runs_of_one_heading_and_non_finite_poses() -> None:
    # the kernel holds the cosine and sine of the last heading: runs of one heading (a
    # lattice block), changes inside a block and NaN headings between equal ones
    from symloc.mcl import rival_search

    rng = np.random.default_rng(5)
    _, field = _field(rng)
    heads = np.repeat(rng.uniform(-4, 4, 40), rng.integers(1, 60, 40))
    n = heads.size
    poses = np.column_stack([rng.uniform(-1, 3, n), rng.uniform(-1, 2.5, n), heads])
    poses[rng.random(n) < 0.02, 2] = np.nan
    poses[rng.random(n) < 0.01, 0] = np.inf
    pts = rng.uniform(-2, 2, (25, 2))
    got = rival_search.match_scores(field, poses, pts, 0.2)
    r = np.hypot(pts[:, 0], pts[:, 1])
    a = np.arctan2(pts[:, 1], pts[:, 0])
    ok = np.all(np.isfinite(poses), axis=1)
    idx = endpoint_flat_indices(field, field.grid_frame_poses(poses[ok]), r, a)
    want = np.count_nonzero(field.padded.ravel()[idx] <= np.float32(0.2), axis=1) / 25
    np.testing.assert_array_equal(got[ok], want)
    off = field.max_dist <= np.float32(0.2)  # a non-finite pose reads the off-map value
    np.testing.assert_array_equal(got[~ok], np.full(int((~ok).sum()), 1.0 if off else 0.0))


def test_match_scores_with_tolerances_beyond_the_clip() -> None:
    from symloc.mcl import rival_search

    rng = np.random.default_rng(4)
    _, field = _field(rng)  # clipped at 0.5 m
    poses = np.column_stack(
        [rng.uniform(-1, 3, 2000), rng.uniform(-1, 2.5, 2000), rng.uniform(-4, 4, 2000)]
    )
    pts = rng.uniform(-2, 2, (30, 2))
    tol = np.where(rng.random(30) < 0.5, 0.7, rng.uniform(0.0, 0.5, 30))
    tol[0] = 0.5  # exactly the clip
    got = rival_search.match_scores(field, poses, pts, tol)
    r = np.hypot(pts[:, 0], pts[:, 1])
    a = np.arctan2(pts[:, 1], pts[:, 0])
    idx = endpoint_flat_indices(field, field.grid_frame_poses(poses), r, a)
    want = np.count_nonzero(field.padded.ravel()[idx] <= tol.astype(np.float32), axis=1) / 30
    np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("n", [0, 1, 7, 8, 9, 100, 128, 129, 255, 1000, 4099, 20000])
def test_pairwise_sum_equals_numpy_sum(n: int) -> None:
    rng = np.random.default_rng(n)
    a = rng.standard_normal(n) ** 2 * 10.0 ** rng.uniform(-3, 3, n)
    assert kernels.pairwise_sum(a, 0, n) == np.sum(a)


def test_scan_cost_and_bilinear_equal_numpy() -> None:
    from symloc.grid.fields import surface_distance_field
    from symloc.mcl import scan_to_map as stm

    rng = np.random.default_rng(2)
    rotated, _ = _field(rng)
    grid = OccupancyGrid(rotated.data, 0.05, origin=(-0.4, 0.3, 0.0))

    field = surface_distance_field(grid, 0.8)
    pts = rng.uniform(-2, 2, (150, 2))
    pose = np.array([1.1, 0.7, 0.4])
    cfg = stm.ScanMatchConfig()
    c, s = np.cos(pose[2]), np.sin(pose[2])
    world = np.column_stack(
        [c * pts[:, 0] - s * pts[:, 1] + pose[0], s * pts[:, 0] + c * pts[:, 1] + pose[1]]
    )
    d, grad = stm._bilinear(field, world)
    # the NumPy expressions, through a grid origin rotated by 0 written as a tiny rotation
    o = grid.origin
    res = grid.resolution
    u = np.clip((world[:, 0] - o[0]) / res - 0.5 + 1.0, 0.0, field.padded.shape[1] - 1.000001)
    v = np.clip((world[:, 1] - o[1]) / res - 0.5 + 1.0, 0.0, field.padded.shape[0] - 1.000001)
    i0, j0 = u.astype(np.intp), v.astype(np.intp)
    fu, fv = u - i0, v - j0
    flat, w2 = field.padded.ravel(), field.padded.shape[1]
    base = j0 * w2 + i0
    d00, d10 = flat[base].astype(float), flat[base + 1].astype(float)
    d01, d11 = flat[base + w2].astype(float), flat[base + w2 + 1].astype(float)
    want = (1 - fv) * ((1 - fu) * d00 + fu * d10) + fv * ((1 - fu) * d01 + fu * d11)
    np.testing.assert_array_equal(d, want)
    np.testing.assert_array_equal(grad[:, 0], ((1 - fv) * (d10 - d00) + fv * (d11 - d01)) / res)
    cost = stm._cost(field, pts, pose, cfg)
    assert cost == float(
        0.5 * np.sum(want * want) * cfg.information_scale / (cfg.sigma * cfg.sigma)
    )


def test_free_space_sampler_int32_cells_same_draws() -> None:
    from symloc.mcl.recovery import FreeSpaceSampler

    rng = np.random.default_rng(8)
    grid, _ = _field(rng)
    fs = FreeSpaceSampler(grid)
    np.testing.assert_array_equal(fs.free_cells, np.flatnonzero(grid.free_mask.ravel()))
    assert fs.free_cells.dtype == np.int32
    # the k-th free cell through the block counts is the list's k-th entry
    np.testing.assert_array_equal(fs.nth_free(np.arange(fs.n_free)), fs.free_cells)
    a = fs.sample(500, np.random.default_rng(1))
    # the same poses as the draws from the list of free cells
    monkey = FreeSpaceSampler(grid)
    monkey.nth_free = lambda k: np.flatnonzero(grid.free_mask.ravel())[k]  # type: ignore[method-assign]
    b = monkey.sample(500, np.random.default_rng(1))
    np.testing.assert_array_equal(a, b)
